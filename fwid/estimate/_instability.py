"""Where plain output error is the wrong method: warnings that point to the right one.

Unstable models under output error point to multiple shooting; residuals coloured by process
noise point to the filter-error method.

Output error integrates the model over the whole record from one initial state (Eqs. 10-11).
When the model (at the start values or at the estimate) has an unstable mode whose growth
over the record is large, the simulation diverges: the Gauss-Newton steps are dominated by
the diverging part and the fit is pulled towards a stable model (Jategaonkar 2015, Sec. 9.2,
FVSysID test case 8: plain output error ends with both eigenvalues stable). [`fwid.fit`][]
with `method="multiple-shooting"` integrates over short segments instead
(`fwid.estimate._shooting`).
"""

from __future__ import annotations

from collections.abc import Sequence

import jax
import numpy as np

from ..models._greybox import GreyBoxModel
from ..simulate._experiment import Experiment
from ._warnings import model_error_signature

#: A mode whose amplitude grows by more than this factor over the record makes output error's
#: simulation diverge (for practical purposes).
GROWTH_MAX = 100.0


def largest_growth(model: GreyBoxModel, exps: Sequence[Experiment]) -> tuple[float, float]:
    """`(largest real part of an eigenvalue of A, its growth factor over the longest record)`,
    A linearised at each experiment's initial state and first input (the largest over the
    experiments); `(nan, nan)` for a static model or when A is not finite."""
    if not model.states:
        return float("nan"), float("nan")
    worst, growth = -np.inf, 0.0
    for e in exps:
        A, _ = model.state_matrices(model.params, e.consts, x0=e.x0, u0=e.u[0])
        A = np.asarray(jax.device_get(A), dtype=float)
        if not np.all(np.isfinite(A)):
            return float("nan"), float("nan")
        re = float(np.max(np.linalg.eigvals(A).real))
        t = np.asarray(e.t)
        span = float(t[np.asarray(e.mask) > 0][-1] - t[0])
        worst = max(worst, re)
        growth = max(growth, float(np.exp(min(re * span, 700.0))))
    return worst, growth


def instability_warnings(start_model: GreyBoxModel, model: GreyBoxModel,
                         exps: Sequence[Experiment], names: Sequence[str]) -> list[str]:
    """A sentence when the start model or the estimated one is unstable enough that output
    error's simulation diverges over the record (growth beyond [`GROWTH_MAX`][])."""
    out = []
    for which, m in (("start", start_model), ("estimated", model)):
        re, growth = largest_growth(m, exps)
        if np.isfinite(re) and re > 0 and growth > GROWTH_MAX:
            out.append(
                f"{', '.join(names)}: the {which} {model.name} model is unstable (eigenvalue "
                f"with real part {re:+.3g} 1/s: it grows {growth:.3g} times over the record); "
                "output error's simulation diverges on an unstable vehicle and pulls the "
                "estimates towards a stable model: fit with method='multiple-shooting'")
            break
    return out


def method_hints(start_model: GreyBoxModel, result, exps: Sequence[Experiment],
                 names: Sequence[str]) -> list[str]:
    """The warnings of an output-error `result` that point to another method of
    [`fwid.fit`][]: [`instability_warnings`][], and, when the residuals bear the mark of model
    error (coloured and correlated between outputs, `fwid.estimate._warnings`), the
    filter-error method for flights in turbulence (process noise)."""
    out = instability_warnings(start_model, result.model, exps, names)
    if model_error_signature(result) is not None:
        out.append(f"{', '.join(names)}: the {result.model.name} output-error residuals are "
                   "coloured: if the vehicle flew in turbulence or its own wake (process "
                   "noise), fit with method='filter-error' (a Kalman filter in the "
                   "likelihood), whose innovations should then be white")
    return out
