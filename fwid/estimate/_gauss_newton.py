"""Gauss-Newton with step halving, built from optimistix's parts."""

from collections.abc import Callable

import optimistix as optx
from jaxtyping import PyTree, Scalar


class DampedGaussNewton(optx.AbstractGaussNewton):
    """Gauss-Newton (`optimistix.NewtonDescent` on the residual Jacobian) with a backtracking
    Armijo search: a step that raises the cost, or makes the simulation blow up (a non-finite
    residual fails the Armijo test), is halved until it does not. This is the step control of
    Jategaonkar's output-error method (step halving), the Jacobians come from forward-mode
    autodiff through the diffrax solve.
    """

    rtol: float
    atol: float
    norm: Callable[[PyTree], Scalar]
    descent: optx.NewtonDescent
    search: optx.BacktrackingArmijo
    verbose: Callable[..., None]

    stall_steps: int = 3

    def __init__(self, rtol: float = 1e-10, atol: float = 1e-8, norm=optx.max_norm,
                 stall_steps: int = 3):
        self.rtol = rtol
        self.atol = atol
        self.norm = norm
        self.descent = optx.NewtonDescent()
        self.search = optx.BacktrackingArmijo(decrease_factor=0.5, slope=1e-4)
        self.verbose = lambda **kw: None
        self.stall_steps = stall_steps

    def terminate(self, fn, y, args, options, state, tags):
        # At the optimum a full Gauss-Newton step changes the cost only at roundoff level and
        # the Armijo test may reject it; `stall_steps` rejections in a row (the step halved to
        # 1/2^stall_steps) mean no further decrease is possible: stop, successfully.
        done, result = super().terminate(fn, y, args, options, state, tags)
        return done | (state.num_steps_since_acceptance >= self.stall_steps), result
