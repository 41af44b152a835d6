"""One classical RK4 step between two samples, for the filter-error estimator, which restarts
the integration at every sample.

The step of [`fwid.simulate`][] (classical RK4 at the data's step, Sec. IV.B, with the input
linearly interpolated: its mean at the half step), `fwid.RK4` stepped by hand
(`simulate._rk4.step_interval`), in the signature of the models' `f(x, u, params, consts)`.
"""

from __future__ import annotations

from ..simulation._rk4 import step_interval


def rk4_step(f, x, u0, u1, dt, params, consts):
    """`x(t + dt)` from `x(t)` for `x' = f(x, u, params, consts)`, `u` linear from `u0` to
    `u1` over the step."""
    return step_interval(lambda x_, u, a: f(x_, u, *a), x, 0.0, dt, u0, u1, (params, consts))
