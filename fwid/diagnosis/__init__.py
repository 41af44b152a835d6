"""Gap diagnosis: where the identified model misses, which unmodelled effect explains the miss,
and how far the held-out error shrinks once that effect is added (beyond the paper).

[`fwid.diagnose`][] fits the paper's load model on training flights, maps where it misses on
held-out test flights, tries every effect of [`fwid.CATALOGUE`][] (and rivals outside it)
added to the model, and returns a [`fwid.Diagnosis`][]: the verdict, the ranked candidates,
the explanations the data cannot tell apart, the gap map and the shrink of the simulated
states. `fwid diagnose` does the same from the command line and writes `diagnosis.json`;
the guide's page "Diagnosis" says how to read it. [`fwid.read_reconstruction`][] reads the
`reconstruction.json` beside reconstructed flights, which the diagnosis reports on."""

from ._catalogue import CATALOGUE as CATALOGUE
from ._catalogue import EFFECT_NAMES as EFFECT_NAMES
from ._catalogue import Effect as Effect
from ._diagnose import Diagnosis as Diagnosis
from ._diagnose import diagnose as diagnose
from ._gapmap import BAND_NAMES as BAND_NAMES
from ._gapmap import gap_map as gap_map
from ._provenance import read_reconstruction as read_reconstruction
