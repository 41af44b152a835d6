"""The detection limit of a diagnosis and how it falls with more flights.

The selection names an effect when its cross-fitted block scores `d_j` (`_significance.py`)
pass the one-sided t test at the first round's level and their mean reaches the smallest
gain that counts (`MIN_GAIN`, `_selection.passes`); the verdict then also asks the
confidence set to keep it ahead of `none`: its mean score significantly above the gain it is
charged, `-log(1 - MIN_GAIN)`, at the set's level (`_confidence.LEVEL`, the one-sided test of
`_confidence.parsimonious`). The statistic is a mean over the scoring
blocks of **every** flight, training and test alike (the cross-fit scores each flight's
blocks by a model fitted on the others), so with `m` flights of the same kind (the same
length, so `b` blocks each; the same input and noise, so the same block spread `sd`) and
per-block scores independent given the fit, its standard error is `sd / sqrt(b m)`. The
smallest true gain found with probability `POWER` (`_significance.power_limit`) is then

    limit(m) = 1 - exp(-( max(t_level se_m, -log(1 - MIN_GAIN) + t_LEVEL se_m)
                          + t_POWER se_m )),

which falls like `1 / sqrt(m)` and never below `MIN_GAIN`: a gain at or below it is not
named however many flights are flown.

`sd` is the spread of the first-round block scores (each entry against the baseline alone)
of the entry that gained most, not below the median over the entries. An effect's scores
spread more than noise does: it shows more in the blocks that excite it than in the others,
so the spread grows with the effect (on the benchmark's flights, an effect's own spread is
about its mean score or more, where an entry that fits nothing spreads a few times less).
The strongest entry seen carries that growth; the median is the noise's. Nothing is tuned:
the levels, the power, the floor and the blocks are the selection's and the set's own.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from ._confidence import LEVEL as SET_LEVEL
from ._significance import POWER, Evidence, power_limit

#: Gains [%] whose flight counts `diagnosis.json` gives (`flights_for`).
QUOTED_GAINS = (1, 2, 3, 5)
#: Most flights `flights_needed` searches (beyond: `None`, as for a gain below the floor).
MOST_FLIGHTS = 100_000


@dataclasses.dataclass(frozen=True)
class DetectionLimit:
    """The selection's test on `flights` flights (`train` + `test`) of `blocks` scoring
    blocks, block spread `sd`, at `level`, with the smallest gain `min_gain`."""

    sd: float
    blocks: int
    flights: int
    train: int
    test: int
    level: float
    min_gain: float

    @property
    def blocks_per_flight(self) -> float:
        return self.blocks / self.flights

    def limit(self, flights: int | None = None) -> float:
        """The smallest gain (fraction) found with probability `POWER` with `flights`
        flights of this kind (default: these)."""
        m = self.flights if flights is None else flights
        n = max(1, round(self.blocks_per_flight * m))
        d = power_limit(self.sd, n, self.level, -math.log1p(-self.min_gain), SET_LEVEL)
        return 1.0 - math.exp(-d)

    def flights_needed(self, gain_pct: float) -> int | None:
        """The fewest flights of this kind (training and test together) whose limit is at
        most `gain_pct` %; `None` when no number does (a gain at or below `min_gain`)."""
        g = gain_pct / 100.0
        if g <= self.min_gain or self.limit(MOST_FLIGHTS) > g:
            return None
        lo, hi = 0, 1  # limit(lo) > g >= limit(hi), the limit falls with the flights
        while self.limit(hi) > g:
            lo, hi = hi, 2 * hi
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (mid, hi) if self.limit(mid) > g else (lo, mid)
        return hi

    def as_dict(self) -> dict:
        """`diagnosis.json`'s `detection` block."""
        lim = 100.0 * self.limit()
        floor = 100.0 * self.min_gain
        return {
            "limit_pct": lim,
            "power": POWER,
            "level": self.level,
            "min_gain_pct": floor,
            "flights": self.flights,
            "train_flights": self.train,
            "test_flights": self.test,
            "blocks": self.blocks,
            "blocks_per_flight": self.blocks_per_flight,
            "block_spread": self.sd,
            "rule": (f"limit(m) = 1 - exp(-(max(t_level se, -ln(1 - {self.min_gain:g}) + "
                     f"t_{SET_LEVEL:g} se) + t_{POWER:g} se)), se = {self.sd:.4g} / "
                     f"sqrt({self.blocks_per_flight:.4g} m) for m flights of this kind "
                     f"(training and test together): {lim:.2f} % at m = {self.flights}, "
                     f"falling like 1/sqrt(m) towards {floor:g} %, never below it"),
            "assumption": "more flights of the same kind (length, input, noise), per-block "
                          "scores independent given the fit; the block spread of the entry "
                          "that gained most (not below the median over the entries)",
            "flights_for": {str(g): self.flights_needed(g) for g in QUOTED_GAINS},
        }

    @classmethod
    def from_json(cls, block: dict) -> DetectionLimit:
        """Back from `diagnosis.json`'s `detection` block."""
        return cls(sd=block["block_spread"], blocks=block["blocks"], flights=block["flights"],
                   train=block["train_flights"], test=block["test_flights"],
                   level=block["level"], min_gain=block["min_gain_pct"] / 100.0)


def detection_limit(first: dict[str, Evidence], catalogue: Sequence[str], level: float,
                    min_gain: float, train: int, test: int) -> DetectionLimit | None:
    """The `DetectionLimit` of a diagnosis from its first round's evidence `first` (by
    name) over the `catalogue` entries (names), at that round's `level`, the spread that of
    the entry that gained most, not below the median (module docstring); `None` when no
    entry was scored on at least two blocks."""
    evs = [first[n] for n in catalogue if n in first and first[n].n >= 2]
    if not evs:
        return None
    top = max(evs, key=lambda ev: ev.mean)
    sd = max(float(np.median([np.std(ev.d, ddof=1) for ev in evs])),
             float(np.std(top.d, ddof=1)))
    return DetectionLimit(sd=sd, blocks=evs[0].n, flights=train + test, train=train,
                          test=test, level=level, min_gain=min_gain)


def flights_needed(detection: dict, gain_pct: float) -> int | None:
    """From `diagnosis.json`'s `detection` block: the fewest flights of the same kind
    (training and test together) that find a `gain_pct` % gain with its power; `None` for a
    gain no number of flights finds."""
    return DetectionLimit.from_json(detection).flights_needed(gain_pct)
