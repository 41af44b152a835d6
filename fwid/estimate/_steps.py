"""One classical RK4 step between two samples, for the estimators that restart the
integration at every sample (filter error) or every few samples (multiple shooting).

The same numbers as [`fwid.simulate`][] (classical RK4 at the data's step, Sec. IV.B, with the
input linearly interpolated: its mean at the half step), written as a plain function for
`lax.scan`: it compiles in a fraction of the time of a diffrax solve.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def rk4_step(f, x, u0, u1, dt, params, consts):
    """`x(t + dt)` from `x(t)` for `x' = f(x, u, params, consts)`, `u` linear from `u0` to
    `u1` over the step."""
    um = 0.5 * (u0 + u1)
    k1 = f(x, u0, params, consts)
    k2 = f(x + 0.5 * dt * k1, um, params, consts)
    k3 = f(x + 0.5 * dt * k2, um, params, consts)
    k4 = f(x + dt * k3, u1, params, consts)
    return x + dt / 6.0 * (k1 + 2.0 * (k2 + k3) + k4)


def rk4_trajectory(f, x0, u, dt, params, consts):
    """The states at every sample, `(n, nx)`, from `x0` at the first sample of `u` `(n, nu)`."""
    def step(x, uu):
        x1 = rk4_step(f, x, uu[0], uu[1], dt, params, consts)
        return x1, x1

    _, xs = jax.lax.scan(step, x0, (u[:-1], u[1:]))
    return jnp.concatenate([x0[None], xs], axis=0)
