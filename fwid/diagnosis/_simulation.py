"""The gap where a user sees it: the simulated cycle-averaged states, before and after the
diagnosed effects are put into the equations of motion.

The baseline (Eq. 7 or 8) and the augmented model (`_augment.py`) are each fitted jointly to
the training flights by output-error ML (Eqs. 10-11, `fwid.identify(joint=True)`), then
simulated on the test flights with only their bias terms re-estimated (as any validation
flight). The RMS of simulated minus measured cycle-averaged states is compared per state.

Each fit takes its measurement-noise covariance R as `fwid.identify` does (`noise="auto"`):
a full R, or a diagonal one where the residuals carry model error, as the baseline's do when
the effect is there. A diagonal R for both was tried: on the raw-take benchmark's lagging
actuators the augmented model, whose residuals are then white and correlated between the
states (one tracking system measures them all), fits worse under it, and the simulated shrink
read 40-52 % instead of 59-69 % (`benchmarks/raw_diagnosis.py --half heldout`).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from .._errors import ExcitationError, FitDivergedError
from ..data import Flight
from ..estimate import least_squares_start, quiet_fits
from ..identification import Identification, get_model, identify
from ..simulation import averaged
from ._augment import augment, prepared_inputs


@dataclasses.dataclass
class SimulationGap:
    """`summary`: the `simulation` block of `diagnosis.json`; `baseline`, `augmented`: the
    two identifications (the augmented one is the model to carry on with; `None` when the
    verdict has no form inside the cycle-averaged EOM)."""

    summary: dict
    baseline: Identification
    augmented: Identification | None
    #: Adds the inputs the augmented model reads to a flight (`summary["prepared_inputs"]`
    #: says what they are): apply it to new flights before simulating them with the model.
    prepare: Callable[[Flight], Flight] | None = None


def _rms_by_state(ident: Identification, states: Sequence[str]) -> dict:
    return {s: float(np.sqrt(np.mean(np.concatenate(
        [(v.simulated[s] - v.measured[s]) ** 2 for v in ident.validation])))) for s in states}


#: A simulated error this many times the measured signal's own RMS is a simulation that
#: diverged (an unstable identified model run open loop), not a misfit.
DIVERGED = 10.0


def _diverged(ident: Identification, errors: dict) -> list[str]:
    """The states whose simulated error on the test flights exceeds `DIVERGED` times the
    measured signal's RMS (about its mean)."""
    out = []
    for s, e in errors.items():
        x = np.concatenate([v.measured[s] for v in ident.validation])
        if e > DIVERGED * max(float(np.std(x)), np.finfo(float).tiny):
            out.append(s)
    return out


def fit_baseline(train: Sequence[Flight], test: Sequence[Flight], axis: str,
                 cutoff: float = 5.0) -> Identification:
    """The baseline (Eq. 7 or 8) fitted jointly on `train`, validated on `test`. It misses
    the effect by design, so its fit warnings (coloured residuals, slow convergence) are
    expected: kept in its fits (`FitResult.warnings`), not issued (`quiet_fits`, which also
    holds when this runs in a worker thread beside the rest of the diagnosis)."""
    with quiet_fits():
        return identify(list(train), get_model(axis), validate=list(test), joint=True,
                        cutoff=cutoff)


def fit_augmented(train: Sequence[Flight], test: Sequence[Flight], axis: str,
                  effects: Sequence[tuple[str, object]], cutoff: float,
                  ) -> tuple[Identification | None, str | None, list]:
    """The model augmented with `effects` fitted jointly on `train`, validated on `test`.
    It starts where the baseline's fit starts, the baseline's least-squares (equation-error)
    values, with the new terms at zero (their own equation-error start can make the
    simulation blow up): it needs nothing of the baseline's fit. It may still miss part of
    the effect, so its fit warnings (coloured residuals, slow convergence) are expected:
    kept in its fits (`quiet_fits`), not issued.

    **Returns:** `(identification, failed, warnings)`: the identification (`None` when no
    effect has a form in the EOM, or the fit failed), why it failed (recorded, not raised)
    and its fits' warnings.
    """
    base = get_model(axis)
    model, prepare, left_out = augment(axis, effects, cutoff)
    in_eom = [n for n, _ in effects if n not in left_out]
    if not in_eom:
        return None, None, []
    try:
        with quiet_fits():
            start = least_squares_start(base, [averaged(f, base, cutoff) for f in train])
            fitted = {k: float(v) for k, v in start.params.items() if k not in base.local}
            after = identify([prepare(f) for f in train], model.with_params(fitted),
                             validate=[prepare(f) for f in test], joint=True, cutoff=cutoff,
                             start="model")
    except (FitDivergedError, ExcitationError, np.linalg.LinAlgError) as exc:
        return None, (f"the model with {' + '.join(in_eom)} in the EOM could not be fitted "
                      f"and simulated ({exc}): the simulated gap is not measured"), []
    return after, None, [m for f in after.fits for m in f.warnings]


class EarlyFits:
    """The block's output-error fits, begun before the verdict is known, in worker threads
    beside the selection (NumPy's; JAX releases the interpreter while it computes): the
    baseline's at once (it does not depend on the verdict), and each augmented model that
    `start` is given (the selection's first-round leader) as soon as it is, beside the
    baseline's. `baseline` is the baseline's future,
    `get(effects)` the augmented fit for `effects` (`None`: none started);
    `simulation_gap` takes the one for the verdict's effects (the rest is left unused)."""

    def __init__(self, train: Sequence[Flight], test: Sequence[Flight], axis: str,
                 cutoff: float):
        self.args, self.cutoff = (list(train), list(test), axis), cutoff
        self._pool = ThreadPoolExecutor(2, thread_name_prefix="fwid-fits")
        self.baseline: Future = self._pool.submit(fit_baseline, *self.args, cutoff)
        self.started: dict[str, Future] = {}

    def start(self, effects: Sequence[tuple[str, object]]) -> None:
        self.started[repr(list(effects))] = self._pool.submit(
            fit_augmented, *self.args, list(effects), self.cutoff)

    def get(self, effects: Sequence[tuple[str, object]]) -> Future | None:
        return self.started.get(repr(list(effects)))

    def close(self) -> None:
        """No more fits: the threads end with the last ones started."""
        self._pool.shutdown(wait=False)


def simulation_gap(train: Sequence[Flight], test: Sequence[Flight], axis: str,
                   effects: Sequence[tuple[str, object]], cutoff: float = 5.0,
                   baseline: Identification | None = None,
                   augmented: Future | None = None) -> SimulationGap:
    """Fit the baseline (or take `baseline`, `fit_baseline`'s result) and the model augmented
    with `effects` (`(name, variant)` pairs; or take `augmented`, `EarlyFits.get`'s future
    for the same effects) on `train`, simulate both on `test`;
    `shrink_pct` is the drop of the RMS of the simulated states,
    `100 (1 - sqrt(mean_s (after_s / before_s)^2))` over the states."""
    base = get_model(axis)
    states = list(base.outputs)
    _, prepare, left_out = augment(axis, effects, cutoff)
    in_eom = [n for n, _ in effects if n not in left_out]
    before_id = fit_baseline(train, test, axis, cutoff) if baseline is None else baseline
    if augmented is not None:
        after_id, failed, fit_warnings = augmented.result()
        caught = []
    else:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            after_id, failed, fit_warnings = fit_augmented(train, test, axis, effects, cutoff)
    before = _rms_by_state(before_id, states)
    after = _rms_by_state(after_id, states) if after_id is not None else dict(before)
    base_ok = bool(all(f.converged for f in before_id.fits))
    augmented_ok = bool(failed is None and (after_id is None
                                            or all(f.converged for f in after_id.fits)))
    ratio = np.mean([(after[s] / before[s]) ** 2 for s in states if before[s] > 0])
    diverged = sorted(set(_diverged(before_id, before))
                      | set(_diverged(after_id, after) if after_id is not None else ()))
    message = failed or (f"the simulation diverges on the test flights ({', '.join(diverged)} "
                         f"off by more than {DIVERGED:g} times their own RMS: an unstable model "
                         "run open loop), so it says nothing of the effect; see "
                         "simulation.warnings" if diverged else None)
    summary = {
        "states": states,
        "effects": in_eom,
        "left_out": left_out,
        "prepared_inputs": prepared_inputs(axis, [(n, v) for n, v in effects
                                                  if n not in left_out]),
        "test_rms_before": before,
        "test_rms_after": None if failed else after,
        "shrink_pct": None if failed or diverged else 100.0 * (1.0 - math.sqrt(float(ratio))),
        "converged": bool(base_ok and augmented_ok),
        # which fit did not: the baseline's (its error, and so the shrink, may be overstated)
        # or the augmented model's (the shrink may be understated)
        "converged_baseline": base_ok,
        "converged_augmented": augmented_ok,
        # the states whose simulation diverged (error over DIVERGED x the signal): no shrink
        "diverged": diverged,
        "warnings": sorted({str(w.message).split(": ", 1)[-1] for w in caught}
                           | {m.split(": ", 1)[-1] for m in fit_warnings}
                           | {m.split(": ", 1)[-1] for f in before_id.fits
                              for m in f.warnings}),
        **({"message": message} if message else {}),
        "method": "baseline and augmented model fitted jointly on the training flights "
                  "(output-error ML, Eqs. 10-11), simulated on the test flights with their "
                  "bias terms re-estimated",
    }
    return SimulationGap(summary, before_id, after_id, prepare)
