"""Sensitivities through the identification pipeline, by JAX autodiff.

Derivatives of what the pipeline produces with respect to what goes into it:

- [`fwid.output_sensitivity`][]: the simulated outputs `y(t)` of the grey-box
  model (Eq. 7 integrated by RK4, Sec. IV.B) with respect to the parameters, the per-flight
  constants (trim `u0 w0 theta0`, `mass`, `Iy`, ...) or the initial state;
- [`fwid.eigenvalue_sensitivity`][]: the eigenvalues of `A = df/dx`
  (Tables 3 and 6), the natural frequency and damping of the oscillatory mode, with respect
  to the parameters and the constants; [`fwid.rank_sensitivities`][] orders them by
  normalised sensitivity `(p / lambda) d lambda / d p`;
- [`fwid.metric_sensitivity`][]: the gradient of the fit cost (Eq. 10, with R
  fixed or from Eq. 11) and of the per-output metrics (Tables 2, 5, 8);
- [`fwid.estimate_sensitivity_to_cutoff`][] and [`fwid.cutoff_cost`][]: how
  the ML estimates move with the 5 Hz split (Sec. III.B), by the implicit function theorem.

Everything is forward mode (`jax.jacfwd`, forward-over-forward for second derivatives): the
simulation is differentiated through diffrax with `diffrax.ForwardMode`. All functions are
pure: they read the model, the data and the fit, and return new arrays.
"""

from ._cutoff import (
    cutoff_cost as cutoff_cost,
    estimate_sensitivity_to_cutoff as estimate_sensitivity_to_cutoff,
)
from ._eigenvalues import (
    eigenvalue_sensitivity as eigenvalue_sensitivity,
    rank_sensitivities as rank_sensitivities,
)
from ._metrics import METRICS as METRICS, metric_sensitivity as metric_sensitivity
from ._outputs import output_sensitivity as output_sensitivity
