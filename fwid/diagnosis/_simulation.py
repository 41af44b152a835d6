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

from .._errors import DiagnosisWarning, ExcitationError, FitDivergedError
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


#: The prior's standard deviation, relative to `max(1, |value|)`, that holds a bias term the
#: flights cannot identify at its equation-error start value (`identify_pinned`).
PIN_STD = 1e-9
#: Refits `identify_pinned` tries, each pinning the terms the last one could not identify.
PIN_TRIES = 3


def _bias_terms(names: Sequence[str], model, n_flights: int) -> bool:
    """Whether every name of `names` is a bias (per-flight) term of `model`: flight `i`'s
    copy `k@i` in a joint fit of several flights, `k` itself in a fit of one."""
    return bool(names) and all(n.split("@")[0] in model.local and ("@" in n) == (n_flights > 1)
                               for n in names)


def identify_pinned(train: Sequence[Flight], test: Sequence[Flight], model, cutoff: float,
                    **kw) -> Identification:
    """`identify(train, model, validate=test, joint=True, cutoff=cutoff, **kw)` (fit
    warnings kept, not issued: `quiet_fits`) that does not stop at a bias term the flights
    cannot identify. Where the estimator finds no information on some flight's bias terms
    (an `ExcitationError` naming only per-flight copies such as `bq@1`), they are held at
    their equation-error start values (`least_squares_start` of the baseline of the model's
    axis on `train`, through a Gaussian prior of `PIN_STD` relative spread on exactly those
    copies) and the fit is run again, up to `PIN_TRIES` times. Any other `ExcitationError` (a
    parameter every flight shares) is raised. The terms held are the identification's
    `pinned` (`{name: value}`, empty when none)."""
    pins: dict[str, tuple[float, float]] = {}
    for tries in range(PIN_TRIES + 1):
        try:
            with quiet_fits():
                out = identify(list(train), model, validate=list(test), joint=True,
                               cutoff=cutoff, prior=pins or None, **kw)
            return dataclasses.replace(out, pinned={k: m for k, (m, _) in pins.items()})
        except ExcitationError as exc:
            new = [n for n in exc.parameters if n not in pins]
            if tries == PIN_TRIES or not new or not _bias_terms(exc.parameters, model,
                                                                 len(train)):
                raise
        base = get_model(model.name.split("+")[0])
        start = least_squares_start(base, [averaged(f, base, cutoff) for f in train])
        for n in new:
            v = float(start.params[n.split("@")[0]])
            pins[n] = (v, PIN_STD * max(1.0, abs(v)))
    raise AssertionError("unreachable")  # the last try returns or raises


def fit_baseline(train: Sequence[Flight], test: Sequence[Flight], axis: str,
                 cutoff: float = 5.0) -> Identification:
    """The baseline (Eq. 7 or 8) fitted jointly on `train`, validated on `test`. It misses
    the effect by design, so its fit warnings (coloured residuals, slow convergence) are
    expected: kept in its fits (`FitResult.warnings`), not issued (`quiet_fits`, which also
    holds when this runs in a worker thread beside the rest of the diagnosis)."""
    return identify_pinned(train, test, get_model(axis), cutoff)


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
            after = identify_pinned([prepare(f) for f in train], [prepare(f) for f in test],
                                    model.with_params(fitted), cutoff, start="model")
    except (FitDivergedError, ExcitationError, np.linalg.LinAlgError) as exc:
        return None, (f"the model with {' + '.join(in_eom)} in the EOM could not be fitted "
                      f"and simulated ({exc}): the simulated gap is not measured"), []
    return after, None, [m for f in after.fits for m in f.warnings]


def fixed_text(fixed: dict) -> str | None:
    """The sentence on the bias terms `identify_pinned` held (`fixed_bias_terms` of the
    block: per model, `{name: value}`), or `None` when none was."""
    parts = [f"{', '.join(f'{k} = {v:.4g}' for k, v in terms.items())} in the {which} model"
             for which, terms in fixed.items() if terms]
    if not parts:
        return None
    return ("simulation: the flights carry no information on the bias terms "
            + "; ".join(parts) + " (too little excitation on those flights): held at their "
            "equation-error start values, the fit went on")


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
    fixed = {"baseline": dict(getattr(before_id, "pinned", {})),
             "augmented": dict(getattr(after_id, "pinned", {}) if after_id is not None else {})}
    note = fixed_text(fixed)
    if note:
        warnings.warn(note, DiagnosisWarning, stacklevel=2)
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
                              for m in f.warnings}
                           | ({note} if note else set())),
        # bias terms the flights carry no information on, held at their equation-error
        # start values so that the fit goes on (`identify_pinned`)
        "fixed_bias_terms": fixed,
        **({"message": message} if message else {}),
        "method": "baseline and augmented model fitted jointly on the training flights "
                  "(output-error ML, Eqs. 10-11), simulated on the test flights with their "
                  "bias terms re-estimated",
    }
    return SimulationGap(summary, before_id, after_id, prepare)
