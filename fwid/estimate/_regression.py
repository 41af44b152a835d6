"""Equation error by linear(ised) least squares: the regression behind the start values.

The least-squares start (Sec. IV.B) regresses measured quantities (reconstructed forces,
differentiated measured states, measured outputs) on the model's functions evaluated at the
measured states and inputs. [`stacked`][] builds the scaled residual and its Jacobian over
all experiments, [`gauss_newton_lstsq`][] solves it (exactly, in one step, when the
parameters enter linearly).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


def derivative(t, x):
    """The time derivative of sampled `x` (central differences)."""
    return np.gradient(np.asarray(x), np.asarray(t), axis=0)


@eqx.filter_jit
def _residual_jacobian(fn, params, names, theta, e, target, scales):
    """`(target - fn(x, u, p, c)) / scales` over one experiment's samples (`x = e.z`),
    flattened, and its Jacobian in the parameters `names` (at `theta`). Compiled once per
    model, function and flight length: the parameters, the data and the constants are
    arguments."""

    def residual(th):
        p = {**params, **dict(zip(names, th))}
        return ((target - jax.vmap(lambda x, u: fn(x, u, p, e.consts))(e.z, e.u))
                / scales).ravel()

    return residual(theta), jax.jacfwd(residual)(theta)


def stacked(fn, params, names, exps, targets, scales):
    """`residual_jacobian(theta)`: [`_residual_jacobian`][] over all `exps` (their `z`
    taken as the states), stacked."""
    params = {k: jnp.asarray(v, dtype=float) for k, v in params.items()}
    scales = jnp.asarray(scales)

    def residual_jacobian(theta):
        parts = [_residual_jacobian(fn, params, tuple(names), theta, e, y, scales)
                 for e, y in zip(exps, targets)]
        return (np.concatenate([np.asarray(r) for r, _ in parts]),
                np.concatenate([np.asarray(J) for _, J in parts]))

    return residual_jacobian


def gauss_newton_lstsq(residual_jacobian, theta, iters=3):
    """A few Gauss-Newton steps with a minimum-norm least-squares solve (exact if affine)."""
    for _ in range(iters):
        r, J = residual_jacobian(theta)
        ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
        if not ok.any():
            break
        step, *_ = np.linalg.lstsq(J[ok], -r[ok], rcond=None)
        theta = theta + step
    return theta
