"""Simulation of a grey-box model with measured inputs, integrated with diffrax."""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from ..models._greybox import GreyBoxModel, Params, as_arrays
from ._experiment import Experiment
from ._parallel_time import solve_affine_at_samples, solve_affine_sensitivities, use_parallel
from ._rk4 import step_interval


def input_at(tau, t0, dt, u: Float[Array, "n nu"]) -> Float[Array, " nu"]:
    """Measured inputs linearly interpolated on their uniform grid at time `tau`."""
    s = (tau - t0) / dt
    k = jnp.clip(jnp.floor(s).astype(int), 0, u.shape[0] - 2)
    a = s - k
    return (1.0 - a) * u[k] + a * u[k + 1]


@eqx.filter_jit
def _solve_at_samples(f: Callable, y0, t: Float[Array, " n"], u: Float[Array, "n nu"],
                      args=None):
    """Classical RK4 (Sec. IV.B) of `x' = f(x, u, args)` from `t[0]`, one step per sample
    interval, the solution at every sample `(n, ...)`; forward-mode differentiable.

    fwid's [`fwid.RK4`][] diffrax solver, stepped by hand (`step_interval`) in a `lax.scan`
    over the sample intervals. `diffrax.diffeqsolve` with `StepTo` the
    sample times gives the same numbers (to round-off) but its loop's bookkeeping (step-size
    controller, saving, events, error codes) cost as much again as the RK4 stages on a
    4-state model: the outputs and sensitivities of one 900-sample flight took 1.9 ms
    instead of 1.1 ms (minimum of 300 interleaved calls, 2-core CPU)."""
    def step(y, interval):
        y1 = step_interval(f, y, *interval, args)
        return y1, y1

    _, ys = lax.scan(step, y0, (t[:-1], t[1:], u[:-1], u[1:]))
    return jax.tree.map(lambda a, b: jnp.concatenate([a[None], b], axis=0), y0, ys)


def _model_field(x, uk, args):
    model, params, consts = args
    return model.f(x, uk, params, consts)


def simulate(
    model: GreyBoxModel,
    exp: Experiment,
    params: Params | None = None,
    *,
    x0: Float[Array, " nx"] | None = None,
    time_parallel: bool | str = "auto",
) -> tuple[Float[Array, "n nx"], Float[Array, "n ny"]]:
    """Simulate `model` over one experiment: classical RK4 at the data's step (Sec. IV.B).

    The inputs are linearly interpolated between samples (at the RK4 half steps); the state
    is saved at every sample. Forward- and reverse-mode autodiff through the solve are
    supported (a `lax.scan` of the diffrax solver's steps).

    **Arguments:**
    - `model`: the [`fwid.GreyBoxModel`][].
    - `exp`: the [`fwid.Experiment`][] giving time, inputs, constants and `x0`.
    - `params`: the full parameter dict (default: `model.params`).
    - `x0`: the initial state (default: `exp.x0`).
    - `time_parallel`: `True` composes the RK4 steps of a model affine in its state with an
      associative scan (parallel in time, `_parallel_time.py`; the same numbers to round-off),
      `False` steps them in turn, `"auto"` (default) takes the parallel path where it is
      faster (on a GPU or TPU) and the model is affine in its state, else the sequential one.

    **Returns:** the states `(n, states)` and outputs `(n, outputs)` at the sample times.
    """
    params = model.params if params is None else params
    x0 = exp.x0 if x0 is None else x0
    t = exp.t
    if len(model.states) == 0:  # a static (input-output) model, e.g. the Fourier series
        xs = jnp.zeros((t.shape[0], 0))
        return xs, _outputs(model, xs, exp.u, params, exp.consts)
    args = (model, params, exp.consts)
    if use_parallel(time_parallel, _model_field, x0, exp.u[0], args):
        xs = solve_affine_at_samples(_model_field, x0, t, exp.u, args)
    else:
        xs = _solve_at_samples(_model_field, x0, t, exp.u, args)
    ys = _outputs(model, xs, exp.u, params, exp.consts)
    return xs, ys


def simulate_sensitivities(
    model: GreyBoxModel,
    exp: Experiment,
    params_of: Callable[[Float[Array, " p"]], Params],
    theta: Float[Array, " p"],
    *,
    time_parallel: bool | str = "auto",
    paired: bool = False,
) -> tuple[Float[Array, "n ny"], Float[Array, "n ny p"]]:
    """The outputs and their derivatives with respect to `theta` (the model's parameters are
    `params_of(theta)`), from one RK4 solve of the state and its forward sensitivities.

    The sensitivity equations `dS/dt = df/dx S + df/dtheta` (`S = dx/dtheta`, `S(0) = 0`)
    are integrated alongside the state with the same RK4 steps; an explicit Runge-Kutta
    method commutes with differentiation, so `dys` equals `jax.jacfwd` of [`fwid.simulate`][]
    (to round-off), at about half the cost: the solver's loop carries one augmented state
    instead of pushing 16 tangents through its bookkeeping.

    `time_parallel` as in [`fwid.simulate`][]: on the parallel path the state and the
    sensitivities are each an associative scan of the same affine steps
    (`_parallel_time.solve_affine_sensitivities`; the same numbers to round-off).
    `paired=True` carries the state and its sensitivities as a pair of arrays instead of one
    (no slicing and joining at every stage): under `jax.vmap` over many flights (`fit_each`)
    the kernel is 20-30 % faster (64 flights, 2-core CPU), for one flight alone 30 % slower,
    so only the batched fits ask for it; the same numbers to round-off.

    **Returns:** the outputs `(n, outputs)` and `d outputs / d theta`, `(n, outputs, p)`.
    """
    p = theta.shape[0]
    eye = jnp.eye(p, dtype=theta.dtype)
    t = exp.t
    consts = exp.consts

    def jvps(fn, x, S):
        """`fn(x, theta)` and its derivative `dfn/dx S + dfn/dtheta`; `S` and the derivative
        are stored parameter-major, `(p, ...)` (no transposes inside the solver's loop)."""
        return jax.vmap(lambda s, e: jax.jvp(fn, (x, theta), (s, e)),
                        out_axes=(None, 0))(S, eye)

    if len(model.states) == 0:
        def h_static(uk):
            return model.h(jnp.zeros(0), uk, params_of(theta), consts)
        ys = jax.vmap(h_static)(exp.u)
        dys = jax.vmap(lambda uk: jax.jacfwd(
            lambda th: model.h(jnp.zeros(0), uk, params_of(th), consts))(theta))(exp.u)
        return ys, dys

    nx = len(model.states)

    def field(x, uk, th):
        return model.f(x, uk, params_of(th), consts)

    if use_parallel(time_parallel, field, exp.x0, exp.u[0], theta):
        xs, Ss = solve_affine_sensitivities(field, exp.x0, t, exp.u, theta)  # (n, p, nx)
    else:
        S0 = jnp.zeros((p, nx), dtype=theta.dtype)
        if paired:  # x `(nx,)` and dx/dtheta `(p, nx)` side by side
            def vector_field(y, uk, args):
                del args
                return jvps(lambda x, th: field(x, uk, th), *y)

            xs, Ss = _solve_at_samples(vector_field, (exp.x0, S0), t, exp.u)
        else:  # in one array: row 0 is x, rows 1.. dx/dtheta_i
            def vector_field(y, uk, args):
                del args
                fx, dS = jvps(lambda x, th: field(x, uk, th), y[0], y[1:])
                return jnp.concatenate([fx[None], dS], axis=0)

            y0 = jnp.concatenate([exp.x0[None], S0], axis=0)
            ys_aug = _solve_at_samples(vector_field, y0, t, exp.u)
            xs, Ss = ys_aug[:, 0], ys_aug[:, 1:]  # (n, nx), (n, p, nx)
    if model.outputs_are_states:
        return xs, jnp.swapaxes(Ss, 1, 2)
    ys, dys = jax.vmap(lambda x, S, uk: jvps(
        lambda x_, th: model.h(x_, uk, params_of(th), consts), x, S))(xs, Ss, exp.u)
    return ys, jnp.swapaxes(dys, 1, 2)


def _outputs(model, xs, u, params, consts):
    if model.outputs_are_states:
        return xs
    return jax.vmap(lambda x, uk: model.h(x, uk, params, consts))(xs, u)


def simulate_forces(model: GreyBoxModel, xs, exp: Experiment, params: Params | None = None):
    """The model's aerodynamic forces and moments (Eqs. 1-6) along a simulated trajectory.

    **Arguments:**

    - `model`: a [`fwid.GreyBoxModel`][] with a force model.
    - `xs`: the simulated states, shape `(n, nx)` (from [`fwid.simulate`][]).
    - `exp`: the [`fwid.Experiment`][] that was simulated (its inputs and constants).
    - `params`: parameter values by name (default: the model's).

    **Returns:** the forces and moments along the trajectory, shape `(n, nf)`, in the order of
    the model's force outputs (N, N m).
    """
    params = model.params if params is None else params
    if model.forces is None:
        raise ValueError(f"model {model.name!r} has no force model")
    return _forces_along(model.forces, xs, exp.u, as_arrays(params), as_arrays(exp.consts))


@eqx.filter_jit
def _forces_along(forces, xs, u, params, consts):
    """`forces` at every sample: one compiled program per force model and shape (called op
    by op after a fit, it compiled a handful of small programs in every new process)."""
    return jax.vmap(lambda x, uk: forces(x, uk, params, consts))(xs, u)
