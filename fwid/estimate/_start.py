"""Least-squares start values: equation error on the reconstructed forces (Sec. IV.B)."""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..models._greybox import GreyBoxModel
from ..simulate._experiment import Experiment
from ._start_outputs import nominal_start


def _derivative(t, x):
    return np.gradient(np.asarray(x), np.asarray(t), axis=0)


@eqx.filter_jit
def _residual_jacobian(fn, params, names, theta, e, target, scales):
    """`(target - fn(x, u, p, c)) / scales` over one experiment's samples, flattened, and
    its Jacobian in the parameters `names` (at `theta`). Compiled once per model, function
    and flight length: the parameters, the data and the constants are arguments."""

    def residual(th):
        p = {**params, **dict(zip(names, th))}
        return ((target - jax.vmap(lambda x, u: fn(x, u, p, e.consts))(e.z, e.u))
                / scales).ravel()

    return residual(theta), jax.jacfwd(residual)(theta)


def _stacked(fn, params, names, exps, targets, scales):
    """`residual_jacobian(theta)`: [`_residual_jacobian`][] over all `exps`, stacked."""
    params = {k: jnp.asarray(v, dtype=float) for k, v in params.items()}
    scales = jnp.asarray(scales)

    def residual_jacobian(theta):
        parts = [_residual_jacobian(fn, params, tuple(names), theta, e, y, scales)
                 for e, y in zip(exps, targets)]
        return (np.concatenate([np.asarray(r) for r, _ in parts]),
                np.concatenate([np.asarray(J) for _, J in parts]))

    return residual_jacobian


def _gauss_newton_lstsq(residual_jacobian, theta, iters=3):
    """A few Gauss-Newton steps with a minimum-norm least-squares solve (exact if affine)."""
    for _ in range(iters):
        r, J = residual_jacobian(theta)
        ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
        if not ok.any():
            break
        step, *_ = np.linalg.lstsq(J[ok], -r[ok], rcond=None)
        theta = theta + step
    return theta


def least_squares_start(model: GreyBoxModel, exps: Sequence[Experiment]) -> GreyBoxModel:
    """Start values for the output-error fit by linear regression (equation error).

    The paper regresses the reconstructed aerodynamic forces and moments on the measured
    states and inputs (Eqs. 1-6); fwid does that for every parameter that enters the force
    model when the flights carry the forces. The remaining free parameters (biases, or all of
    them for a model with no force model, such as the ATTAS short-period model) come from
    regressing the numerically differentiated measured states on `f(x, u, p, c)`.

    **Returns:** the model with its free parameters set to the least-squares values.
    """
    free = list(model.free)
    params = dict(model.params)
    use_forces = model.forces is not None and all(e.forces is not None for e in exps)
    force_free: list[str] = []
    if use_forces:
        # Which free parameters does the force model depend on? (the first flight tells)
        e0 = exps[0]
        _, dF = _stacked(model.forces, params, free, exps[:1], [e0.forces], 1.0)(
            jnp.stack([jnp.asarray(params[k], dtype=float) for k in free]))
        force_free = [k for i, k in enumerate(free) if np.any(dF[:, i] != 0)]

        scales = np.concatenate([np.asarray(e.forces) for e in exps]).std(axis=0) + 1e-300
        force_rj = _stacked(model.forces, params, force_free, exps, [e.forces for e in exps],
                            scales)
        th = _gauss_newton_lstsq(force_rj, jnp.stack([params[k] for k in force_free]))
        params.update(dict(zip(force_free, th)))

    rest = [k for k in free if k not in force_free]
    if rest and model.outputs_are_states:
        xdots = [_derivative(e.t, e.z) for e in exps]
        scales = np.concatenate(xdots).std(axis=0) + 1e-300
        state_rj = _stacked(model.f, params, rest, exps, [jnp.asarray(x) for x in xdots],
                            scales)
        th = _gauss_newton_lstsq(state_rj, jnp.stack([params[k] for k in rest]))
        params.update(dict(zip(rest, th)))
    else:
        nominal_start(model, rest)
    return model.with_params(params)
