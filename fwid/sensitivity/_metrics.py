"""Gradients of the fit cost (Eq. 10) and of the per-output fit metrics (Tables 2, 5, 8)
with respect to the parameters."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ._common import _check_single, _full_params, _pick_names, output_jacobian

METRICS = ("cost", "rms", "rms_pct", "r2", "corr")


def _metrics(y, z, mask, Rinv, logdetR):
    """The cost of Eq. 10 (R given) and the per-output metrics of `fit_metrics`, masked."""
    m = mask[:, None]
    N = jnp.sum(mask)
    ny = z.shape[-1]
    v = (z - y) * m
    cost = (0.5 * jnp.einsum("ki,ij,kj->", v, Rinv, v) + 0.5 * N * logdetR
            + 0.5 * N * ny * jnp.log(2 * jnp.pi))
    rms = jnp.sqrt(jnp.sum(v**2, axis=0) / N)
    zbar = jnp.sum(z * m, axis=0) / N
    ybar = jnp.sum(y * m, axis=0) / N
    zc, yc = (z - zbar) * m, (y - ybar) * m
    sst = jnp.sum(zc**2, axis=0)
    big, small = jnp.max(jnp.where(m > 0, z, -jnp.inf), axis=0), \
        jnp.min(jnp.where(m > 0, z, jnp.inf), axis=0)
    return dict(
        cost=cost,
        rms=rms,
        rms_pct=100.0 * rms / (big - small),
        r2=1.0 - jnp.sum(v**2, axis=0) / sst,
        corr=jnp.sum(zc * yc, axis=0) / jnp.sqrt(sst * jnp.sum(yc**2, axis=0)),
    )


@jax.jit
def _metric_gradients(y, S, z, mask, R):
    """The metrics at `y` and their derivatives along each output sensitivity in `S`."""
    if R is None:  # Eq. 11 at these parameters
        v = (z - y) * mask[:, None]
        R = v.T @ v / jnp.sum(mask)
    Rinv = jnp.linalg.inv(R)
    logdet = jnp.linalg.slogdet(R)[1]

    def f(yy):
        return _metrics(yy, z, mask, Rinv, logdet)

    grad = {k: jax.jvp(f, (y,), (s,))[1] for k, s in S.items()}
    return f(y), grad, R


def metric_sensitivity(
    model: GreyBoxModel,
    exp: Experiment,
    params: Mapping[str, float] | None = None,
    *,
    R: Float[Array, "ny ny"] | None = None,
    names: Sequence[str] | None = None,
) -> dict:
    """Gradients of the fit cost (Eq. 10) and of the per-output fit metrics.

    With respect to the parameters (or the names given).

    The cost is the output-error negative log-likelihood of Eq. (10),

    $$J(\\theta) = \\frac12 \\sum_k v_k^T R^{-1} v_k + \\frac{N}{2}\\ln\\det R
    + \\frac{N n_y}{2}\\ln 2\\pi, \\qquad v_k = z_k - y_k(\\theta),$$

    with `R` held fixed, so `dJ/dtheta = -sum_k (dy_k/dtheta)^T R^{-1} v_k`. Without `R`, R is
    Eq. (11) at `params`; then `J` equals the concentrated cost `N/2 ln det R(theta) + const`
    that [`fwid.fit`][] reports, and (R being its minimiser) so does the gradient: it is zero
    at a converged estimate. The per-output metrics are those of
    [`fwid.validate.fit_metrics`][] (Tables 2, 5, 8): `rms`, `rms_pct`, `r2`, `corr`
    (computed over the experiment's unmasked samples). All derivatives are exact (forward
    mode through the simulation, then the chain rule).

    **Arguments:**
    - `model`, `exp`: the model and one [`fwid.Experiment`][].
    - `params`: where to evaluate (default: the model's values).
    - `R`: the noise covariance to hold fixed, e.g. a [`fwid.FitResult`][]'s `R`.
    - `names`: the parameters to differentiate with respect to (default: the free ones).

    **Returns:** `{metric: {"value": ..., "grad": {name: ...}}}` for `metric` in `"cost"`
    (scalars) and `"rms"`, `"rms_pct"`, `"r2"`, `"corr"` (arrays `(ny,)`, by output), plus
    `"outputs"` (the output names) and `"R"` (the covariance used).
    """
    _check_single(exp, "metric_sensitivity")
    p = _full_params(model, params)
    names = _pick_names(model.param_names, names if names is not None else model.free,
                        "parameters")
    Rj = None if R is None else jnp.asarray(R, dtype=float)
    y, S = output_jacobian(model, exp, p, names, "params")  # shared with output_sensitivity
    value, grad, R_used = _metric_gradients(y, S, exp.z, exp.mask, Rj)
    out: dict = {k: {"value": value[k], "grad": {n: grad[n][k] for n in names}}
                 for k in METRICS}
    out["outputs"] = model.outputs
    out["R"] = R_used
    return out
