"""No silent failure: what a finished output-error fit (Eqs. 10-11) should tell its user.

[`fit_warnings`][] reads a fit's numbers and says, one sentence each, when the fit did not
converge, when the noise covariance R of Eq. (11) is ill-conditioned, when the residuals bear
the mark of model error (coloured and correlated between outputs), when two parameters are
correlated so strongly that the data cannot separate them, or when the estimate or its
uncertainty is not finite. [`fwid.fit`][] and [`fwid.fit_each`][] issue each as a
[`fwid.FitWarning`][] and keep them in `FitResult.warnings`.
"""

from __future__ import annotations

import contextlib
import contextvars
import warnings
from collections.abc import Sequence

import numpy as np
from jaxtyping import ArrayLike, Float

from .._errors import FitWarning
from .._advice import advise

#: R whose correlation form (unit diagonal, so independent of the outputs' units) has a larger
#: condition number is reported as ill-conditioned.
R_COND_MAX = 1e8
#: Parameter pairs correlated beyond this (in absolute value) are reported.
CORR_MAX = 0.98
#: Residuals whose autocorrelation at the data's bandwidth (`FitResult.colour`, see
#: `fwid.estimate._colour`) exceeds this are strongly coloured ... Measured: at most 0.20 for
#: the measurement noise of the low-passed DelFly demo flights (whose autocorrelation at one
#: sample is 0.997), 0.90-0.998 for the model error of the textbook records; 0.5 lies between.
COLOURED = 0.5
#: ... and, correlated between two outputs beyond this, carry the mark of model error (process
#: noise or a missing effect) rather than of measurement noise. On the textbook cases of
#: `benchmarks/textbook_cases.py` the residual correlations are 0.57 (FVSysID TC01, ay and
#: p), 0.85 (TC04) and 0.93 (SIDPAC Twin Otter); on simulated cycle-averaged DelFly flights
#: (`fwid.identify`) up to 0.58, with white residuals at the data's bandwidth.
MODEL_ERROR_CORR = 0.5


def r_condition(R: Float[ArrayLike, "ny ny"]) -> float:
    """The condition number of R in correlation form, `D^-1/2 R D^-1/2` with `D = diag(R)`
    (R of Eq. 11; infinite when R is singular or not finite)."""
    R = np.asarray(R, dtype=float)
    d = np.sqrt(np.abs(np.diag(R)))
    if not (np.all(np.isfinite(R)) and np.all(d > 0)):
        return float("inf")
    return float(np.linalg.cond(R / np.outer(d, d)))


def correlated_pairs(corr: Float[ArrayLike, "p p"], names: Sequence[str],
                     limit: float = CORR_MAX) -> list[tuple[str, str, float]]:
    """The parameter pairs whose estimates are correlated beyond `limit`, strongest first."""
    c = np.asarray(corr, dtype=float)
    i, j = np.triu_indices(len(names), 1)
    keep = np.abs(c[i, j]) > limit
    pairs = [(names[a], names[b], float(c[a, b])) for a, b in zip(i[keep], j[keep])]
    return sorted(pairs, key=lambda p: -abs(p[2]))


def collinear_pairs(M: Float[ArrayLike, "p p"], names: Sequence[str],
                    limit: float = CORR_MAX) -> list[tuple[str, str, float]]:
    """Pairs whose sensitivities are collinear beyond `limit`: the off-diagonal of the
    information matrix `M` scaled to a unit diagonal (where `M` is singular and the
    correlation of the estimates does not exist). Within [-1, 1], as `M` is a Gram matrix."""
    return correlated_pairs(np.clip(_unit_diagonal(M), -1.0, 1.0), names, limit)


def _unit_diagonal(M: Float[ArrayLike, "p p"]) -> np.ndarray:
    """`M` scaled to a unit diagonal, `D^-1/2 M D^-1/2` (0 where a diagonal entry is 0)."""
    M = np.asarray(M, dtype=float)
    d = np.sqrt(np.clip(np.diag(M), 0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(M / np.outer(d, d))


def unidentifiable(M: Float[ArrayLike, "p p"], names: Sequence[str],
                   share: float = 0.1) -> list[str]:
    """The parameters of the direction the information matrix `M` knows least: the
    eigenvector of the smallest eigenvalue of `M` scaled to a unit diagonal, its entries of
    squared size above `share` (largest first). Where `M` is singular, these are the
    parameters whose combination the data cannot fix."""
    S = _unit_diagonal(M)
    if not np.all(np.isfinite(S)):
        return []
    vec = np.linalg.eigh((S + S.T) / 2)[1][:, 0]
    order = np.argsort(-vec**2)
    return [names[i] for i in order if vec[i] ** 2 > share]


def model_error_signature(result) -> tuple[float, str, str, str, float] | None:
    """`(colour, output, a, b, corr)` when the fit's residuals are strongly coloured at the
    data's bandwidth (largest autocorrelation `colour` there, on `output`, beyond
    [`COLOURED`][]) and correlated between outputs `a` and `b` beyond
    [`MODEL_ERROR_CORR`][] (`corr`); `None` otherwise (or when the result does not carry the
    residual statistics)."""
    colour = getattr(result, "colour", None)
    if colour is None or result.residual_corr is None:
        return None
    colour = np.asarray(colour, dtype=float)
    outputs = result.model.outputs
    pairs = correlated_pairs(result.residual_corr, outputs, MODEL_ERROR_CORR)
    if not pairs or not np.nanmax(colour) > COLOURED:
        return None
    k = int(np.nanargmax(colour))
    return float(colour[k]), outputs[k], *pairs[0]


def fit_warnings(result, flights: Sequence[str], max_steps: int | None = None,
                 information: Float[ArrayLike, "p p"] | None = None,
                 method: str = "output-error") -> list[str]:
    """The warnings of one fit (a [`fwid.FitResult`][]), each a sentence that names the
    flights, what is wrong and the one step to take next (`fwid._advice.NEXT` for `method`,
    the estimator that made the fit). `information`: the Fisher information matrix at the
    estimate, to name the parameters that cannot be separated when it is singular."""
    who = f"{', '.join(flights)}: the {result.model.name} fit"
    out = []
    # parameters at an active bound have no std (NaN by design, `FitResult.active`)
    active = getattr(result, "active", None)
    free = (np.ones(len(result.names), bool) if active is None
            else np.asarray(active) == 0)
    if not (np.all(np.isfinite(np.asarray(result.theta)))
            and np.isfinite(float(result.cost))):
        out.append(f"{who} diverged: the simulation or the estimate is not finite (check "
                   f"the units and the trim); next: {advise('diverged', method)}")
    elif not np.all(np.isfinite(np.asarray(result.std)[free])):
        out.append(f"{who} has non-finite standard deviations (the simulation or the "
                   "information matrix is not finite at the estimate): the uncertainty "
                   f"cannot be trusted; next: {advise('diverged', method)}")
    if not bool(result.converged):
        cap = f" (max_steps={max_steps})" if max_steps is not None else ""
        steps = int(result.steps)
        if max_steps is not None and steps < max_steps:  # stopped early, not at the cap
            out.append(f"{who} did not converge: it stopped after {steps} Gauss-Newton "
                       f"step{'s' if steps != 1 else ''}{cap} because no shorter step "
                       "lowered the cost (a flat or ragged likelihood there); the estimates "
                       f"may be far from the optimum; next: {advise('not-converged', method)}")
        else:
            out.append(f"{who} did not converge in {steps} Gauss-Newton "
                       f"step{'s' if steps != 1 else ''}{cap}: "
                       "the estimates may be far from the optimum; next: "
                       f"{advise('not-converged', method)}")
    cond = r_condition(result.R)
    if cond > R_COND_MAX:
        out.append(f"{who}: the noise covariance R is ill-conditioned (condition number "
                   f"{cond:.3g} in correlation form): outputs are nearly linearly dependent "
                   f"or noise-free; next: {advise('ill-conditioned', method)}")
    mark = model_error_signature(result)
    if mark is not None:
        colour, out_k, a, b, c = mark
        out.append(f"{who}: the residuals are strongly coloured (autocorrelation "
                   f"{colour:.3f} on {out_k} at the data's bandwidth) and correlated "
                   f"between outputs ({a} and {b}: "
                   f"{c:+.2f}): process noise or a missing effect, not measurement noise "
                   "(process noise biases output error); "
                   "the standard deviations `std` allow for the colour, `std_cr` does not; "
                   f"next: {advise('model-error', method)}")
    pairs = correlated_pairs(result.corr, result.names)
    corr_free = np.asarray(result.corr)[np.ix_(free, free)]
    if not pairs and information is not None and not np.all(np.isfinite(corr_free)):
        out.append(_singular(who, information, result.names, method))
    elif pairs:
        listed = ", ".join(f"{a} and {b} ({c:+.4f})" for a, b, c in pairs[:5])
        more = f" and {len(pairs) - 5} more" if len(pairs) > 5 else ""
        out.append(f"{who}: parameters nearly unidentifiable, correlated beyond {CORR_MAX}: "
                   f"{listed}{more}; fix one of each pair, next: "
                   f"{advise('singular', method, pairs[0][0])}")
    return out


def _singular(who: str, M, names: Sequence[str], method: str = "output-error") -> str:
    """The warning of a fit whose information matrix `M` is singular to working precision
    (no covariance, no correlation of the estimates): the pairs whose sensitivities are
    collinear, else the parameters of the direction `M` does not know."""
    pairs = collinear_pairs(M, names)
    first = pairs[0][0] if pairs else (unidentifiable(M, names) or ["NAME"])[0]
    if pairs:
        listed = ", ".join(f"{a} and {b} ({c:+.4f})" for a, b, c in pairs[:5])
        more = f" and {len(pairs) - 5} more" if len(pairs) > 5 else ""
        which = (f"the sensitivities of these pairs are collinear beyond {CORR_MAX}: "
                 f"{listed}{more}")
    else:
        which = ("the data do not fix a combination of "
                 + ", ".join(unidentifiable(M, names)[:6]))
    return (f"{who}: the information matrix is singular (to working precision), so the "
            f"estimates have no covariance and no correlation: {which}; fix some of them, "
            f"next: {advise('singular', method, first)}")


#: Set (in this thread or task only) by `quiet_fits`.
_QUIET: contextvars.ContextVar[bool] = contextvars.ContextVar("fwid_quiet_fits", default=False)


@contextlib.contextmanager
def quiet_fits():
    """Inside, fits keep their warnings in `FitResult.warnings` without issuing them. Unlike
    `warnings.catch_warnings`, which swaps process-wide state, it holds for the current
    thread only: a fit run in a worker thread beside other work stays quiet alone."""
    token = _QUIET.set(True)
    try:
        yield
    finally:
        _QUIET.reset(token)


def issue(messages: Sequence[str], stacklevel: int = 3) -> None:
    """Issue each message as a [`fwid.FitWarning`][] (unless inside `quiet_fits`)."""
    if _QUIET.get():
        return
    for m in messages:
        warnings.warn(m, FitWarning, stacklevel=stacklevel)
