"""Gauss-Newton with step halving, built from optimistix's parts."""

from collections.abc import Callable

import equinox as eqx
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import PyTree, Scalar


class _ArmijoWithProgress(optx.AbstractSearch):
    """`optimistix.BacktrackingArmijo`, also remembering the relative cost decrease of the
    last accepted step (so the solver can stop once progress is at roundoff level)."""

    armijo: optx.BacktrackingArmijo

    def init(self, y, f_info_struct):
        return (self.armijo.init(y, f_info_struct), jnp.array(jnp.inf))

    def step(self, first_step, y, y_eval, f_info, f_eval_info, state):
        inner, last = state
        step_size, accept, result, inner = self.armijo.step(
            first_step, y, y_eval, f_info, f_eval_info, inner
        )
        f0, f1 = f_info.as_min(), f_eval_info.as_min()
        rel = (f0 - f1) / jnp.maximum(jnp.abs(f0), jnp.finfo(f0.dtype).tiny)
        last = jnp.where(accept & ~first_step, rel, last)
        return step_size, accept, result, (inner, last)


class DampedGaussNewton(optx.AbstractGaussNewton):
    """Gauss-Newton (`optimistix.NewtonDescent` on the residual Jacobian) with a backtracking
    Armijo search: a step that raises the cost, or makes the simulation blow up (a non-finite
    residual fails the Armijo test), is halved until it does not. This is the step control of
    Jategaonkar's output-error method (step halving); the Jacobians come from forward-mode
    autodiff through the diffrax solve.

    Besides optimistix's Cauchy test on `rtol`/`atol`, the solve stops when an accepted step
    lowers the cost by less than `loss_rtol` (relative), or after `stall_steps` rejected
    halvings in a row: at the optimum a full step changes the cost only at roundoff level.
    """

    rtol: float
    atol: float
    norm: Callable[[PyTree], Scalar]
    descent: optx.NewtonDescent
    search: _ArmijoWithProgress
    verbose: Callable[..., None]
    loss_rtol: float = eqx.field(static=True)
    stall_steps: int = eqx.field(static=True)

    def __init__(self, rtol: float = 1e-10, atol: float = 1e-8, norm=optx.max_norm, *,
                 loss_rtol: float = 1e-13, stall_steps: int = 3):
        self.rtol = rtol
        self.atol = atol
        self.norm = norm
        self.descent = optx.NewtonDescent()
        self.search = _ArmijoWithProgress(optx.BacktrackingArmijo(decrease_factor=0.5, slope=1e-4))
        self.verbose = lambda **kw: None
        self.loss_rtol = loss_rtol
        self.stall_steps = stall_steps

    def terminate(self, fn, y, args, options, state, tags):
        done, result = super().terminate(fn, y, args, options, state, tags)
        _, last_decrease = state.search_state
        stalled = state.num_steps_since_acceptance >= self.stall_steps
        settled = (last_decrease >= 0) & (last_decrease < self.loss_rtol)
        return done | stalled | settled, result


