"""Estimation: the free parameters of a grey-box model from flight data.

[`fwid.fit`][] estimates them by output-error maximum likelihood (Eqs. 10-11 of the paper,
Gauss-Newton with the noise covariance relaxed at every step), or by multiple shooting for
unstable vehicles ([`fwid.fit_shooting`][]) and filter error for flights in turbulence
([`fwid.fit_filter_error`][]). [`fwid.fit_each`][] fits many flights one by one in a single
call, spread over the devices (and, after [`fwid.initialize_distributed`][], over processes).
A prior and bounds ([`fwid.prior_from`][], [`fwid.prior_information`][]) add what is known
before the flight. Every fit returns a [`fwid.FitResult`][]: the estimates, their standard
deviations and correlations, and whether it converged. The guide's pages on identification
and on the prior and bounds show them at work.
"""

from ._gauss_newton import RelaxedGaussNewton as RelaxedGaussNewton
from ._problem import FitResult as FitResult
from ._prior import (
    PriorBounds as PriorBounds,
    bounds_from as bounds_from,
    prior_from as prior_from,
    prior_information as prior_information,
)
from ._fit import METHODS as METHODS, fit as fit
from ._each import fit_each as fit_each
from ._distributed import initialize_distributed as initialize_distributed
from ._start import least_squares_start as least_squares_start
from ._uncertainty import (
    coloured_residual_middle as coloured_residual_middle,
    correlation as correlation,
)
from ._local import refit_local_affine as refit_local_affine
from ._warnings import fit_warnings as fit_warnings, quiet_fits as quiet_fits
from ._shooting import fit_shooting as fit_shooting
from ._filter_error import (
    FilterErrorResult as FilterErrorResult,
    fit_filter_error as fit_filter_error,
)
from ._riccati import steady_state_gain as steady_state_gain
