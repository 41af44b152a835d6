"""Gap diagnosis: where the identified model misses, which unmodelled effect explains the miss,
and how far the held-out error shrinks once that effect is added (beyond the paper)."""

from ._catalogue import CATALOGUE as CATALOGUE
from ._catalogue import EFFECT_NAMES as EFFECT_NAMES
from ._catalogue import Effect as Effect
from ._diagnose import Diagnosis as Diagnosis
from ._diagnose import diagnose as diagnose
from ._gapmap import BAND_NAMES as BAND_NAMES
from ._gapmap import gap_map as gap_map
from ._provenance import read_reconstruction as read_reconstruction
