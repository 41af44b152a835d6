"""Least-squares start values: equation error on the reconstructed forces (Sec. IV.B)."""

from __future__ import annotations

from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from ..models._greybox import GreyBoxModel
from ..simulate._experiment import Experiment
from ._start_outputs import nominal_start


def _derivative(t, x):
    return np.gradient(np.asarray(x), np.asarray(t), axis=0)


def _gauss_newton_lstsq(residual, theta, iters=3):
    """A few Gauss-Newton steps with a minimum-norm least-squares solve (exact if affine)."""
    for _ in range(iters):
        r = np.asarray(residual(theta))
        J = np.asarray(jax.jacfwd(residual)(theta))
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
        # Which free parameters does the force model depend on?
        def forces_of(th):
            p = {**params, **dict(zip(free, th))}
            return jnp.concatenate([
                jax.vmap(lambda x, u: model.forces(x, u, p, e.consts))(e.z, e.u).ravel()
                for e in exps[:1]
            ])

        dF = np.asarray(jax.jacfwd(forces_of)(jnp.stack([params[k] for k in free])))
        force_free = [k for i, k in enumerate(free) if np.any(dF[:, i] != 0)]

        scales = np.concatenate([np.asarray(e.forces) for e in exps]).std(axis=0) + 1e-300

        def force_residual(th):
            p = {**params, **dict(zip(force_free, th))}
            return jnp.concatenate([
                ((e.forces - jax.vmap(lambda x, u: model.forces(x, u, p, e.consts))(e.z, e.u))
                 / scales).ravel()
                for e in exps
            ])

        th = _gauss_newton_lstsq(force_residual, jnp.stack([params[k] for k in force_free]))
        params.update(dict(zip(force_free, th)))

    rest = [k for k in free if k not in force_free]
    if rest and model.outputs_are_states:
        xdots = [_derivative(e.t, e.z) for e in exps]
        scales = np.concatenate(xdots).std(axis=0) + 1e-300

        def state_residual(th):
            p = {**params, **dict(zip(rest, th))}
            return jnp.concatenate([
                ((xd - jax.vmap(lambda x, u: model.f(x, u, p, e.consts))(e.z, e.u))
                 / scales).ravel()
                for e, xd in zip(exps, xdots)
            ])

        th = _gauss_newton_lstsq(state_residual, jnp.stack([params[k] for k in rest]))
        params.update(dict(zip(rest, th)))
    else:
        nominal_start(model, rest)
    return model.with_params(params)
