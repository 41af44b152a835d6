"""Models: the paper's grey-box models, as differentiable pytrees.

A [`fwid.GreyBoxModel`][] holds the state equation, the outputs and the named parameters
(free or fixed) of a model. The paper's models are built by functions:
[`fwid.longitudinal`][] and [`fwid.lateral`][] (the cycle-averaged models, Eqs. 1-9, Tables 1
and 4), [`fwid.fourier_model`][] and [`fwid.fourier_series`][] (the flapping forces as a
Fourier series in the flapping phase, Eq. 12), and [`fwid.combined`][] (both in the equations
of motion, Eqs. 13-15). A model is simulated by `fwid.simulation` and fitted by
`fwid.estimate`; the pipelines of `fwid.identification` build and fit them for you.
"""

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
