"""Test inputs designed through the identified model (the test-input format).

[`fwid.design_input`][] designs the control input of the next flight from an identified model:
the input, within an amplitude, a duration and an attitude limit, that minimises the
predicted parameter variances (or maximises the determinant of the information, D-optimal),
returned as a [`fwid.Design`][] with the predicted standard deviations against a 3211 of the
same amplitude and length. [`fwid.design_discriminating`][] designs the input that best tells
two diagnosed explanations apart ([`fwid.Discrimination`][]). `fwid design` does both from the
command line; the guide's page "Test inputs" shows how.

The modules:

- `_signals.py`: the design grid, the two parametrisations (multisine with free amplitudes and
  phases; a free piecewise-constant sequence) and the classic inputs (doublet, 3211,
  Schroeder-phased multisine, random binary sequence);
- `_information.py`: the Fisher information of the output-error fit as a function of the
  input (the simulation's forward sensitivities), the per-flight biases' Schur complement,
  the prior;
- `_source.py`: the model, constants and noise covariance from a `report.json` or an
  identification;
- `_affine.py`: the responses of a model affine in the input, precomputed (the information a
  quadratic form in the input's coefficients), and the numerical check that it is;
- `_criterion.py`: the criteria (geometric mean of the variances, D-optimal), the
  parametrisations as basis coefficients, the affine criterion as one pytree;
- `_optimise.py`: Adam (optax) over random restarts side by side, and the sign-flip polish;
- `_design.py`: [`fwid.design_input`][], the designed input, and its `Design`;
- `_discriminate.py`: [`fwid.design_discriminating`][], the input that best tells two models
  apart.
"""

from ._design import Design as Design, design_input as design_input
from ._discriminate import (
    Discrimination as Discrimination,
    design_discriminating as design_discriminating,
)


from ._signals import CLASSIC as CLASSIC, Grid as Grid
