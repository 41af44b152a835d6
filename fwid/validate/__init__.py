"""How well an identified model matches the data, and what its dynamics are.

- [`fwid.fit_metrics`][]: RMS, RMS as % of the range, R^2 and correlation per
  output (Tables 2, 5, 8).
- [`fwid.eigenvalues`][], [`fwid.modes`][]: eigenvalues of `A = df/dx` and the
  modes they make (Tables 3 and 6).
- [`fwid.harmonic_amplitudes`][], `nonharmonic_share`: the flapping peaks'
  heights (Figure 12) and the flapping-band energy off the harmonics (Figures 12 vs 14).

The derivatives of all of these are in `fwid.sensitivity`.
"""

from ._harmonics import (
    harmonic_amplitudes as harmonic_amplitudes,
    nonharmonic_share as nonharmonic_share,
)
from ._metrics import fit_metrics as fit_metrics
from ._modes import eigenvalues as eigenvalues, modes as modes
from ._state_space import StateSpace as StateSpace, state_space as state_space
