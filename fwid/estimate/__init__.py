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
