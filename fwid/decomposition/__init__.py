"""Split flight data into the cycle-averaged and the flapping part (Section III.B, Figure 4).

- [`fwid.decomposition.lowpass`][], [`fwid.decomposition.highpass`][]: zero-phase Butterworth filters,
  computed in the frequency domain (differentiable with respect to the cut-off).
- [`fwid.decomposition.decompose`][] -> [`fwid.decomposition.Decomposition`][]: noise low-pass (40 Hz),
  then the split at 5 Hz; [`fwid.decomposition.cycle_averaged`][] and
  [`fwid.decomposition.flapping_part`][] do the same on a `fwid.data.Flight`.
- [`fwid.decomposition.estimate_flapping_frequency`][], [`fwid.decomposition.flapping_phase`][],
  [`fwid.decomposition.check_flapping_frequency`][]: the flapping frequency and phase driving Eq. (12).
"""

from ._filters import highpass as highpass
from ._filters import lowpass as lowpass
from ._filters import squared_gain as squared_gain
from ._frequency import check_flapping_frequency as check_flapping_frequency
from ._frequency import estimate_flapping_frequency as estimate_flapping_frequency
from ._frequency import flapping_phase as flapping_phase
from ._split import Decomposition as Decomposition
from ._split import cycle_averaged as cycle_averaged
from ._split import decompose as decompose
from ._split import SPLIT_ORDER as SPLIT_ORDER
from ._split import edge_samples as edge_samples
from ._split import flapping_part as flapping_part
