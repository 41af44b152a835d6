"""The measurement-noise covariance R of Eqs. (10)-(11): full, diagonal, or a guarded full R.

A full R (Eq. 11) lets the outputs' noise be correlated; when the outputs are nearly linearly
dependent (or one is nearly noise-free) it goes singular and the likelihood wanders off to a
spurious optimum, where a diagonal R (as in FVSysID and SIDPAC) does not. Likewise when
model error rather than measurement noise makes the residuals (coloured, and correlated
between outputs): a full R then weights the outputs by the model error, and the estimates
move by several standard deviations from the diagonal-R ones that the textbooks publish
(FVSysID TC01: 2.3 sd; TC04 and SIDPAC's Twin Otter do not converge in 60 steps and end up
to 6 sd away; see `benchmarks/textbook_cases.py`). `noise="auto"` (the default of
[`fwid.fit`][]) fits with a full R and falls back to a diagonal R when the full fit did not
converge, diverged, ended with an ill-conditioned R, or ended with residuals that carry the
mark of model error ([`model_error_signature`][]); `FitResult.noise` says which R the
estimates belong to.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from .._errors import FitDivergedError
from .._advice import advice
from ._warnings import R_COND_MAX, model_error_signature, r_condition

NOISE_MODELS = ("auto", "full", "diagonal")


def check_noise(noise: str) -> None:
    if noise not in NOISE_MODELS:
        raise ValueError(f"noise must be one of {', '.join(map(repr, NOISE_MODELS))}, "
                         f"not {noise!r}")


def full_r_trouble(result) -> str | None:
    """Why a fit with a full R should not be kept (`None` when it can be)."""
    if not (np.all(np.isfinite(np.asarray(result.theta))) and np.isfinite(float(result.cost))):
        return "was not finite"
    if not bool(result.converged):
        return f"did not converge in {int(result.steps)} Gauss-Newton steps"
    cond = r_condition(result.R)
    if cond > R_COND_MAX:
        return f"ended with an ill-conditioned R (condition number {cond:.3g})"
    mark = model_error_signature(result)
    if mark is not None:
        colour, out_k, a, b, c = mark
        return (f"ended with residuals that model error, not measurement noise, makes "
                f"(autocorrelation {colour:.3f} on {out_k} at the data's bandwidth, {a} and "
                f"{b} correlated {c:+.2f}), which "
                "a full R would weight the outputs by")
    return None


def choose(full, diagonal, reason: str, flights) -> object:
    """The diagonal-R fit when it converged (noting why the full one was dropped), else the
    full-R fit (noting that the diagonal-R refit did not converge either)."""
    if diagonal is None:
        return full
    if not bool(diagonal.converged):
        note = (f"{', '.join(flights)}: the {full.model.name} fit with a full R {reason}, and "
                "the refit with a diagonal R did not converge either; the estimates are "
                "those of the full R")
        return dataclasses.replace(full, warnings=(*full.warnings, note))
    note = (f"{', '.join(flights)}: the {full.model.name} fit with a full R {reason}; the "
            "estimates are those of a diagonal R, which converged; "
            f"{advice('noise-full')} keeps the full R")
    return dataclasses.replace(diagonal, warnings=(note, *diagonal.warnings))


def fall_back(results: Sequence, refit: Callable[[list[int]], list],
              flights: Sequence[Sequence[str]], progress: bool = False) -> list:
    """`noise="auto"` for [`fwid.fit`][] and [`fwid.fit_each`][]: each full-R result (a
    FitResult, or the FitDivergedError its fit raised) that should not be kept is replaced by
    its diagonal-R refit (`refit(indices)`, one result per index) where that converged
    ([`choose`][]); a diverged full-R fit by its refit whatever it gave. `flights`: the
    flights of each result, for the messages."""
    reasons = [("diverged" if isinstance(r, FitDivergedError) else full_r_trouble(r))
               for r in results]
    redo = [i for i, why in enumerate(reasons) if why is not None]
    out = list(results)
    if not redo:
        return out
    if progress:
        print(f"fwid: {len(redo)} fit(s) with a full R failed ("
              + "; ".join(dict.fromkeys(reasons[i] for i in redo))
              + "): refitting with a diagonal R", flush=True)
    for i, d in zip(redo, refit(redo)):
        out[i] = (d if isinstance(results[i], FitDivergedError)
                  else choose(results[i], d, reasons[i], flights[i]))
    return out
