"""Gap diagnosis: where the identified model misses, which unmodelled effect explains the miss,
and how far the held-out error shrinks once that effect is added (beyond the paper)."""

from ._catalogue import CATALOGUE as CATALOGUE, EFFECT_NAMES as EFFECT_NAMES, Effect as Effect
from ._diagnose import Diagnosis as Diagnosis, diagnose as diagnose
from ._gapmap import BAND_NAMES as BAND_NAMES, gap_map as gap_map
