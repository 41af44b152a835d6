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

    def __init__(self, rtol: float = 1e-10, atol: float = 1e-12, norm=optx.max_norm):
        self.rtol = rtol
        self.atol = atol
        self.norm = norm
        self.descent = optx.NewtonDescent()
        self.search = optx.BacktrackingArmijo(decrease_factor=0.5, slope=1e-4)
        self.verbose = lambda **kw: None
