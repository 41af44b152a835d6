"""Simulation of a grey-box model with measured inputs, integrated with diffrax."""

from __future__ import annotations

import diffrax
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..models._greybox import GreyBoxModel, Params
from ._experiment import Experiment
from ._rk4 import RK4


def input_at(tau, t0, dt, u: Float[Array, "n nu"]) -> Float[Array, " nu"]:
    """Measured inputs linearly interpolated on their uniform grid at time `tau`."""
    s = (tau - t0) / dt
    k = jnp.clip(jnp.floor(s).astype(int), 0, u.shape[0] - 2)
    a = s - k
    return (1.0 - a) * u[k] + a * u[k + 1]


def _vector_field(tau, x, args):
    model, params, t0, dt, u, consts = args
    return model.f(x, input_at(tau, t0, dt, u), params, consts)


def simulate(
    model: GreyBoxModel,
    exp: Experiment,
    params: Params | None = None,
    *,
    x0: Float[Array, " nx"] | None = None,
) -> tuple[Float[Array, "n nx"], Float[Array, "n ny"]]:
    """Simulate `model` over one experiment: classical RK4 at the data's step (Sec. IV.B).

    The inputs are linearly interpolated between samples (at the RK4 half steps); the state
    is saved at every sample. Forward-mode autodiff through the solve is supported
    (`diffrax.ForwardMode`), which is what the Gauss-Newton Jacobians use.

    **Arguments:**
    - `model`: the [`fwid.GreyBoxModel`][].
    - `exp`: the [`fwid.Experiment`][] giving time, inputs, constants and `x0`.
    - `params`: the full parameter dict (default: `model.params`).
    - `x0`: the initial state (default: `exp.x0`).

    **Returns:** the states `(n, states)` and outputs `(n, outputs)` at the sample times.
    """
    params = model.params if params is None else params
    x0 = exp.x0 if x0 is None else x0
    t = exp.t
    if len(model.states) == 0:  # a static (input-output) model, e.g. the Fourier series
        xs = jnp.zeros((t.shape[0], 0))
        return xs, _outputs(model, xs, exp.u, params, exp.consts)
    dt = t[1] - t[0]
    args = (model, params, t[0], dt, exp.u, exp.consts)
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_vector_field),
        RK4(),
        t0=t[0],
        t1=t[-1],
        dt0=None,
        y0=x0,
        args=args,
        saveat=diffrax.SaveAt(t0=True, steps=True),
        stepsize_controller=diffrax.StepTo(ts=t),
        adjoint=diffrax.ForwardMode(),
        max_steps=t.shape[0] - 1,
        throw=False,
    )
    xs = sol.ys
    ys = _outputs(model, xs, exp.u, params, exp.consts)
    return xs, ys


def _outputs(model, xs, u, params, consts):
    if model.outputs_are_states:
        return xs


    return jax.vmap(lambda x, uk: model.h(x, uk, params, consts))(xs, u)


def simulate_forces(model: GreyBoxModel, xs, exp: Experiment, params: Params | None = None):
    """The model's aerodynamic forces and moments (Eqs. 1-6) along a simulated trajectory."""


    params = model.params if params is None else params
    if model.forces is None:
        raise ValueError(f"model {model.name!r} has no force model")
    return jax.vmap(lambda x, uk: model.forces(x, uk, params, exp.consts))(xs, exp.u)
