"""The identification pipelines: the stages below joined into the paper's workflows.

- [`fwid.identify`][] -> [`fwid.Identification`][]: the cycle-averaged
  model, Section IV (Eqs. 1-11), per flight or joint, with modes and validation.
- [`fwid.compare_joint`][] -> [`fwid.JointComparison`][]: a joint fit against
  individual fits on held-out flights.
- [`fwid.identify_flapping_model`][] -> [`fwid.FlappingIdentification`][]:
  the Fourier model of the flapping forces, Section V (Eq. 12).
- [`fwid.steady_vs_manoeuvre`][] -> [`fwid.SteadyVsManoeuvre`][]: the flapping
  model on a flight's quiet start vs its manoeuvre (Figures 12, 14).
- [`fwid.identify_combined`][] -> [`fwid.CombinedIdentification`][]: both
  parts in the EOM, Section VI (Eqs. 13-15).

What they share: [`fwid.FlightFit`][] and [`fwid.evaluate`][] (a model's response on one
flight and its metrics). Reports, summaries and figures of every pipeline are in
`fwid.report`; the command line is in `fwid.cli`.
"""

from ._combined import (
    CombinedIdentification as CombinedIdentification,
    combined_experiment as combined_experiment,
    identify_combined as identify_combined,
)
from ._cycle_averaged import (
    MODELS as MODELS,
    Identification as Identification,
    get_model as get_model,
    identify as identify,
)
from ._flapping import (
    FlappingIdentification as FlappingIdentification,
    identify_flapping_model as identify_flapping_model,
)
from ._flapping_data import flapping_data as flapping_data, flight_axis as flight_axis
from ._flight_fit import FlightFit as FlightFit, evaluate as evaluate
from ._joint import JointComparison as JointComparison, compare_joint as compare_joint
from ._steady import SteadyVsManoeuvre as SteadyVsManoeuvre, steady_vs_manoeuvre as steady_vs_manoeuvre
