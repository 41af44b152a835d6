"""One classical RK4 step between two samples, for the estimators that restart the
integration at every sample (filter error) or every few samples (multiple shooting).

The step of [`fwid.simulate`][] (classical RK4 at the data's step, Sec. IV.B, with the input
linearly interpolated: its mean at the half step), `fwid.RK4` stepped by hand
(`simulate._rk4.step_interval`), in the signature of the models' `f(x, u, params, consts)`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..simulate._rk4 import step_interval


def rk4_step(f, x, u0, u1, dt, params, consts):
    """`x(t + dt)` from `x(t)` for `x' = f(x, u, params, consts)`, `u` linear from `u0` to
    `u1` over the step."""
    return step_interval(lambda x_, u, a: f(x_, u, *a), x, 0.0, dt, u0, u1, (params, consts))


def rk4_trajectory(f, x0, u, dt, params, consts):
    """The states at every sample, `(n, nx)`, from `x0` at the first sample of `u` `(n, nu)`."""
    def step(x, uu):
        x1 = rk4_step(f, x, uu[0], uu[1], dt, params, consts)
        return x1, x1

    _, xs = jax.lax.scan(step, x0, (u[:-1], u[1:]))
    return jnp.concatenate([x0[None], xs], axis=0)
