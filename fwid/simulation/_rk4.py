"""The classical fourth-order Runge-Kutta method as a diffrax solver (diffrax ships none)."""

from collections.abc import Callable
from typing import ClassVar

import diffrax
import jax
import jax.numpy as jnp


def _axpy(a, x, y):
    """`y + a * x` on pytrees."""
    return jax.tree.map(lambda xi, yi: yi + a * xi, x, y)


class RK4(diffrax.AbstractSolver):
    """Classical RK4 with fixed steps, the integrator of the paper's estimator (Sec. IV.B).

    fwid steps it by hand, one step per sample interval (`_simulate._solve_at_samples`);
    with `diffrax.diffeqsolve` use a fixed step size controller (`diffrax.StepTo`).

    Written as a plain `diffrax.AbstractSolver` rather than a Butcher tableau: diffrax's
    general explicit Runge-Kutta machinery (stage buffers, the embedded error estimate, FSAL
    bookkeeping) costs more than the four stages themselves on a 4-state model, and its
    forward-mode Jacobian about 2.5x more. The numbers are those of the tableau
    `c = (0, 1/2, 1/2, 1)`, `b = (1/6, 1/3, 1/3, 1/6)`; there is no error estimate (fixed
    steps only). Dense output is the cubic Hermite interpolant on the first and last stage.

    **Arguments:** none (`fwid.RK4()`); use it as any diffrax solver.
    """

    term_structure: ClassVar = diffrax.AbstractTerm
    interpolation_cls: ClassVar[Callable[..., diffrax.ThirdOrderHermitePolynomialInterpolation]] = (
        diffrax.ThirdOrderHermitePolynomialInterpolation.from_k
    )

    def order(self, terms):
        del terms
        return 4

    def init(self, terms, t0, t1, y0, args):
        del terms, t0, t1, y0, args
        return None

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        del solver_state, made_jump
        control = terms.contr(t0, t1)
        th = t0 + 0.5 * (t1 - t0)
        k1 = terms.vf_prod(t0, y0, args, control)
        k2 = terms.vf_prod(th, _axpy(0.5, k1, y0), args, control)
        k3 = terms.vf_prod(th, _axpy(0.5, k2, y0), args, control)
        k4 = terms.vf_prod(t1, _axpy(1.0, k3, y0), args, control)
        y1 = jax.tree.map(lambda y, a, b, c, d: y + (a + 2.0 * (b + c) + d) / 6.0,
                          y0, k1, k2, k3, k4)
        k = jax.tree.map(lambda a, d: jnp.stack([a, d]), k1, k4)
        dense_info = dict(y0=y0, y1=y1, k=k)
        return y1, None, dense_info, None, diffrax.RESULTS.successful

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)


def interval_field(f: Callable):
    """`f(x, u, args)` as a diffrax vector field on one sample interval: its `args` are the
    interval `(ta, tb, ua, ub, args)`, the input linearly interpolated between the interval's
    two samples (what [`fwid.input_at`][] gives there, without indexing the whole record)."""

    def vector_field(tau, x, interval):
        ta, tb, ua, ub, args = interval
        w = (tau - ta) / (tb - ta)
        return f(x, ua + w * (ub - ua), args)

    return vector_field


def step_interval(f: Callable, y, ta, tb, ua, ub, args=None):
    """One [`RK4`][] step of `y' = f(y, u, args)` from `ta` to `tb`, the input linear from
    `ua` to `ub` (its mean at the half step): the step of every fwid simulation, stepped by
    hand (diffrax's "step manually" use of a solver; `RK4` keeps no solver state)."""
    term = diffrax.ODETerm(interval_field(f))
    y1, _, _, _, _ = RK4().step(term, ta, tb, y, (ta, tb, ua, ub, args), None, False)
    return y1
