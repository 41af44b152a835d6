"""Process noise as the evidence for a `random-disturbance` verdict.

The colour of the held-out load residual (`_disturbance.py`) says that nothing measured
predicts what is left; the filter-error method (Jategaonkar 2015, Ch. 5;
[`fwid.estimate.fit_filter_error`][]) says how much random forcing of the states it takes
to explain the training flights. The baseline cycle-averaged model (Eq. 7 or 8) is fitted
jointly to the training flights' cycle-averaged parts (the data of the baseline's
output-error fit in `_simulation.py`, each flight with its own bias terms) with a
steady-state Kalman filter in the likelihood (Eqs. 5.36, 5.45-5.48): the process-noise
matrix F (diagonal, one entry per state: `dx = f dt + F dw`, `w` a unit Wiener process) is
estimated with the parameters, and the filter's innovations should be white where the
model plus process noise explain the data.

The cycle-averaged states are low-passed at the split (`cutoff`, 5 Hz) and sampled far
faster: their measurement noise is correlated over many samples, which the filter (white
measurement noise) cannot tell from process noise. The fit therefore runs on every
`round(1 / (2 cutoff dt))`-th sample (the band's Nyquist rate, 0.1 s at 5 Hz), where the
low-passed noise is about white, and the innovations' whiteness (autocorrelation at lags
1..20 within the 95 % band, at most 10 % of them outside, `_filter_error.whiteness`) is
judged there.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np

from ..data import Flight
from ..estimate import fit_filter_error
from ..estimate._filter_error import WHITENESS_LAGS, WHITENESS_OUTSIDE_MAX
from ..identification import get_model
from ..simulation import Experiment
from ..simulation._averaged import averaged

#: The confidence of the whiteness band (`+-1.96 / sqrt(N)`).
WHITENESS_BAND = 0.95


def band_rate(e: Experiment, cutoff: float) -> Experiment:
    """`e` at every `k = round(1 / (2 cutoff dt))`-th sample (at least every one): sampled
    at the Nyquist rate of a signal low-passed at `cutoff` [Hz]."""
    k = max(1, round(1.0 / (2.0 * cutoff * float(e.t[1] - e.t[0]))))
    forces = None if e.forces is None else e.forces[::k]
    return Experiment(e.t[::k], e.u[::k], e.z[::k], x0=e.x0, consts=e.consts, forces=forces)


def process_noise(train: Sequence[Flight], axis: str, cutoff: float = 5.0) -> dict:
    """The `process_noise` block of `diagnosis.json`: the baseline of `axis` fitted by filter
    error to the training flights (see the module docstring).

    **Keys:** `method` (`"filter-error"`), `flights`, `sample_s` (the filter's step),
    `F` (per state, state units per sqrt(s)), `F_rel` (per measured state, the process
    noise's increment over one filter step, `F sqrt(sample_s)`, over the RMS of the measured
    state's change per step: near 0 where the state moves as the model says, of order 1
    where random forcing dominates its motion; `None` for an unmeasured state), `innovations_white` and `innovations_outside_pct` (per output: the
    share of lags 1..`whiteness_lags` outside the band), `whiteness_band` (0.95),
    `whiteness_lags`, `whiteness_outside_max_pct`, `converged`, `passes` (relaxations of
    R), `warnings` (the fit's, one sentence each) and, where the fit failed, `message` and
    `failed` (the error, one line; then `converged` is false and there are no estimates).
    Never raises for a failed fit: the block is evidence, not a requirement of the verdict.
    """
    model = get_model(axis)
    names = [f.name for f in train]
    block = {"method": "filter-error", "flights": names, "whiteness_band": WHITENESS_BAND,
             "whiteness_lags": WHITENESS_LAGS,
             "whiteness_outside_max_pct": 100.0 * WHITENESS_OUTSIDE_MAX}
    try:
        exps = [band_rate(averaged(f, model, cutoff), cutoff) for f in train]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = fit_filter_error(model, exps, names=names, local_per_flight=True)
    except Exception as err:  # noqa: BLE001 (any failure is recorded, the diagnosis goes on)
        reason = " ".join(f"{type(err).__name__}: {err}".split())
        return {**block, "converged": False, "message": reason, "failed": reason}
    F = {s: float(v) for s, v in zip(model.states, np.asarray(res.F))}
    dt = float(exps[0].t[1] - exps[0].t[0])
    F_rel = {}
    for s in model.states:
        if s not in model.outputs:
            F_rel[s] = None
            continue
        j = model.outputs.index(s)
        step = np.concatenate([np.diff(np.asarray(e.z)[:, j]) for e in exps])
        size = float(np.sqrt(np.mean(step ** 2)))
        F_rel[s] = float(F[s] * np.sqrt(dt) / size) if size > 0 else None
    white = res.whiteness or {}
    return {**block, "sample_s": dt, "F": F, "F_rel": F_rel,
            "innovations_white": {k: bool(w["white"]) for k, w in white.items()},
            "innovations_outside_pct": {k: float(w["outside_pct"]) for k, w in white.items()},
            "converged": bool(res.converged), "passes": int(res.outer),
            "warnings": sorted({str(w.message).split(": ", 1)[-1] for w in caught})}
