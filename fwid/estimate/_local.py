"""Re-estimating a model's flight-specific parameters (bias terms) on a new flight."""

from __future__ import annotations

import numpy as np

from .._errors import FitDivergedError
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate


#: Eigenvalues of the residual covariance below this share of its largest are raised to it
#: (outputs whose residuals are nearly proportional, as a diverging simulation makes them).
FLOOR = 1e-12


def _whitener(R: np.ndarray) -> np.ndarray:
    """`W` with `W^T W = R^-1` for a covariance `R`, its eigenvalues floored at `FLOOR` times
    the largest (a Cholesky factor fails on a singular `R`)."""
    lam, V = np.linalg.eigh(0.5 * (R + R.T))
    top = max(float(lam.max()), np.finfo(float).tiny)
    return (V / np.sqrt(np.maximum(lam, FLOOR * top))).T


def refit_local_affine(model: GreyBoxModel, exp: Experiment, *, passes: int = 20):
    """ML estimate of the bias terms (`model.local`) on one flight, all else held, for a model
    whose outputs are affine in them (Eq. 7 with biases: `x' = A x + B u + b`).

    The same estimate as `fwid.fit(model.with_free(model.local), ...)` (Eqs. 10-11 with R
    relaxed), computed from `1 + len(local)` simulations by iteratively re-weighted linear
    least squares, so validating the cycle-averaged part does not compile a second estimator.

    **Returns:** the bias values by name, or `None` when the outputs are not affine in them.
    """
    local = list(model.local)
    b0 = {k: 0.0 for k in local}
    step = 1e-2

    def sim(values):
        return np.asarray(simulate(model.with_params(values), exp)[1])

    y0 = sim(b0)
    with np.errstate(invalid="ignore", over="ignore"):  # a diverging model: raised below
        S = np.stack([(sim({**b0, k: step}) - y0) / step for k in local], axis=-1)  # (n, ny, p)
    if not (np.all(np.isfinite(y0)) and np.all(np.isfinite(S))):
        raise FitDivergedError("the model's simulation of the flight is not finite: it "
                               "diverges on this flight's inputs")
    z = np.asarray(exp.z)
    keep = np.asarray(exp.mask) > 0
    z, y0, S = z[keep], y0[keep], S[keep]
    r0 = z - y0
    b = np.zeros(len(local))
    R = r0.T @ r0 / r0.shape[0]
    for _ in range(passes):
        Linv = _whitener(R)
        A = np.einsum("ij,njp->nip", Linv, S).reshape(-1, len(local))
        rhs = (r0 @ Linv.T).reshape(-1)
        b_new, *_ = np.linalg.lstsq(A, rhs, rcond=None)
        v = r0 - np.einsum("njp,p->nj", S, b_new)
        R = v.T @ v / v.shape[0]
        done = np.allclose(b_new, b, rtol=1e-10, atol=1e-14)
        b = b_new
        if done:
            break
    values = dict(zip(local, b.tolist()))
    # affine? the prediction must match a simulation at the estimate
    y_hat = sim(values)[keep]
    pred = y0 + np.einsum("njp,p->nj", S, b)
    if not np.allclose(y_hat, pred, rtol=1e-6, atol=1e-9 * (np.abs(y_hat).max() + 1e-300)):
        return None
    return values
