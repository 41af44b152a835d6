from ._delfly import (
    TABLE1 as TABLE1,
    TABLE4 as TABLE4,
    heading_rate as heading_rate,
    lateral as lateral,
    longitudinal as longitudinal,
)
from ._greybox import GreyBoxModel as GreyBoxModel, Params as Params
from ._combined import combined as combined, force_parts as force_parts
from ._fourier import (
    estimate_phase_offset as estimate_phase_offset,
    fourier_least_squares as fourier_least_squares,
    fourier_model as fourier_model,
    fourier_param_names as fourier_param_names,
    fourier_regressors as fourier_regressors,
    fourier_series as fourier_series,
    shift_phase as shift_phase,
)
