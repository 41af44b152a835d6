"""Is a candidate effect real? Out-of-sample evidence pooled over loads, tested across blocks.

The evidence is a **cross-fit**: the model with and without the candidate is fitted on the
training flights and scored on the test flights, and fitted on the test flights and scored on
the training flights; with few flights, each of `FEW_FLIGHTS_FOLDS` groups of flights is scored
by the model fitted on all the others (`cross_fit_folds`). Every flight is cut into scoring blocks of about `BLOCK_S` seconds (its
trim load and Fourier coefficients re-estimated on each block, as the baseline does per
flight), so a campaign of a few flights still gives tens of scores, and the many samples inside
each flight count, while the residuals' colour (always present in reconstructed loads, Morelli
& Klein 1995) stays inside a block.

Per block `j`, the statistic pools the loads of the candidate's band, each scaled by the
baseline's training mean square `s_l`:

    d_j = log( sum_l SSE_j,l(without) / s_l  /  sum_l SSE_j,l(with) / s_l ).

Given the fit, blocks are independent, and when the candidate explains nothing its extra
coefficients only add error on data it was not fitted to, so `E[d_j] <= 0`. A one-sided t test
on the `d_j` is therefore valid without a model of the noise, and over-fitting costs a candidate
instead of helping it. One decision per candidate; the level is corrected over the candidates
still in play (Holm-style forward selection, `_selection.py`), not over loads.

The *detection limit* is the held-out error reduction the test would have detected with
probability `POWER`, given the spread of the block scores: the smallest effect it could see.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import stats

from ._attribution import Engine, Model
from ._catalogue import Effect

#: Length [s] of a scoring block.
BLOCK_S = 1.0
#: Power at which the detection limit is quoted.
POWER = 0.8
#: Folds of the cross-fit (at most one per flight). Two: training vs test. More group the
#: flights round-robin and score each group's blocks by the model fitted on all the others,
#: so each fit sees more flights: what matters when there are few.
FOLDS = 2
#: Folds when there are at most `FEW_FLIGHTS` flights in all. On the development half of
#: `benchmarks/diagnosis_power.py` with 4+4 flights, eight named 91 instead of 86 of 112
#: single effects, with the same false alarms (1 of 20). With more flights each fit already
#: sees enough of them; there eight folds cost time and, with 8+8 flights, turn the near tie
#: between `unsteady-aero` and the attitude probe on a load that follows the attitude
#: (held-out gains 13.4 % and 13.3 %) the other way, so two stay.
FEW_FLIGHTS_FOLDS = 8
FEW_FLIGHTS = 8


def default_folds(n_flights: int) -> int:
    """`FEW_FLIGHTS_FOLDS` for a campaign of at most `FEW_FLIGHTS` flights, else `FOLDS`."""
    return FEW_FLIGHTS_FOLDS if n_flights <= FEW_FLIGHTS else FOLDS


@dataclasses.dataclass(frozen=True)
class Half:
    """One direction of the cross-fit: fit on units `fit`, score on units `score` (blocks),
    with the baseline's training mean square `sigma2` per channel for scaling."""

    fit: tuple[int, ...]
    score: tuple[int, ...]
    sigma2: dict


@dataclasses.dataclass
class Evidence:
    """Out-of-sample evidence for one candidate added to a model."""

    effect: str
    variants: tuple  # chosen on each half's fit units (`OnLoads`)
    d: np.ndarray  # per scoring block, pooled log ratio
    before: dict  # per load: held-out SSE summed over blocks, without the candidate
    after: dict  # and with it

    @property
    def n(self) -> int:
        return len(self.d)

    @property
    def mean(self) -> float:
        return float(np.mean(self.d))

    @property
    def t(self) -> float:
        sd = float(np.std(self.d, ddof=1)) if self.n > 1 else math.inf
        if sd == 0.0:
            return math.inf if self.mean > 0 else -math.inf
        return self.mean / (sd / math.sqrt(self.n))

    @property
    def p(self) -> float:
        """One-sided p value of `mean d > 0`."""
        return float(stats.t.sf(self.t, df=max(self.n - 1, 1)))

    @property
    def gain(self) -> float:
        """Typical relative drop of a block's held-out error (`1 - exp(-mean d)`)."""
        return 1.0 - math.exp(-self.mean)

    def detection_limit(self, level: float) -> float:
        """Smallest typical relative drop of the held-out error detectable at `level` with
        probability `POWER` (same block spread)."""
        if self.n < 2:
            return 1.0
        return 1.0 - math.exp(-power_limit(float(np.std(self.d, ddof=1)), self.n, level))

    def load_gain(self) -> dict:
        """Per load: relative drop of the held-out sum of squares."""
        return {ld: 1.0 - self.after[ld] / self.before[ld] if self.before[ld] > 0 else 0.0
                for ld in self.before}

    def as_dict(self, level: float) -> dict:
        return {
            "p": self.p,
            "t": self.t,
            "blocks": self.n,
            "blocks_better": int(np.sum(self.d > 0)),
            "heldout_gain_pct": 100.0 * self.gain,
            "detection_limit_pct": 100.0 * self.detection_limit(level),
            "load_gain_pct": {ld: 100.0 * g for ld, g in self.load_gain().items()},
        }


def power_limit(sd: float, n: int, level: float, floor: float = 0.0,
                floor_level: float | None = None) -> float:
    """The true mean block score `d` that the test passes with probability `POWER`: `n`
    blocks of spread `sd`, the one-sided t test at `level` and, with `floor > 0`, the mean
    also at least `floor` (the selection's smallest gain, `-log(1 - MIN_GAIN)`), or, with
    `floor_level`, significantly above `floor` at that level (the confidence set's test of
    an effect against `none` with the gain it is charged). The estimated mean is the true
    one plus `sd / sqrt(n)` times a t variate, so it exceeds the larger of the bars with
    probability `POWER` when the true mean is that bar plus the `POWER` quantile of the t
    times the standard error. `inf` for fewer than 2 blocks."""
    if n < 2:
        return math.inf
    df = n - 1
    se = sd / math.sqrt(n)
    above = 0.0 if floor_level is None else stats.t.isf(floor_level, df) * se
    return max(stats.t.isf(level, df) * se, floor + above) + stats.t.isf(1.0 - POWER, df) * se


def evidence(engine: Engine, halves: list[Half], models: list[Model], effect: Effect) -> Evidence:
    """The cross-fitted evidence for adding `effect` to `models` (one per half)."""
    chans = engine.channels(effect.band)
    d, variants = [], []
    before = np.zeros(len(chans))
    after = np.zeros(len(chans))
    for half, model in zip(halves, models):
        v = engine.choose(half.fit, model, effect, half.sigma2)
        eb = engine.block_errors(half.fit, half.score, model, effect.band)
        ea = engine.block_errors(half.fit, half.score, model + ((effect, v),), effect.band)
        w = np.array([1.0 / half.sigma2[ch] for ch in chans])
        d.append(np.log(np.maximum(eb @ w, 1e-300) / np.maximum(ea @ w, 1e-300)))
        before += eb.sum(axis=0)
        after += ea.sum(axis=0)
        variants.append(v)
    loads = [ch[0] for ch in chans]
    return Evidence(effect.name, tuple(variants), np.concatenate(d),
                    dict(zip(loads, before)), dict(zip(loads, after)))


def cross_fit_folds(engine: Engine, n_flights: int, block_parents, n_train: int,
                    folds: int | None = None) -> list[Half]:
    """The folds of the cross-fit: with 2, the training flights fitted and the test flights'
    blocks scored, and the other way round; with more, the flights (units `0..n_flights-1`,
    the first `n_train` the training ones) grouped round-robin into `folds` groups, in the
    order of (training/test, name, length), so that the order they were given in does not
    matter; each group's blocks are scored by the model fitted on all the other flights
    (the blocks follow the flights: unit `n_flights + j` is a block of flight
    `block_parents[j]`)."""
    k = min(default_folds(n_flights) if folds is None else folds, n_flights)
    if k <= 2:
        groups = [tuple(range(n_train, n_flights)), tuple(range(n_train))]
    else:
        order = sorted(range(n_flights), key=lambda i: (i >= n_train, engine.units[i].signals.name,
                                                        engine.units[i].signals.n, i))
        groups = [tuple(sorted(order[g::k])) for g in range(k)]
    out = []
    for g in groups:
        fit = tuple(i for i in range(n_flights) if i not in g)
        score = tuple(n_flights + j for j, p in enumerate(block_parents) if p in g)
        out.append(Half(fit, score, engine.mean_square(fit)))
    return out


def block_count(s) -> int:
    """How many scoring blocks of about `BLOCK_S` seconds the flight signals `s` make."""
    return max(1, round(s.n * s.dt / BLOCK_S))


def scoring_blocks(sigs, first: int) -> tuple[list, list]:
    """Each flight (unit `first + k`) cut into scoring blocks of about `BLOCK_S` seconds:
    the blocks' signals and their `(parent unit, rows)`."""
    out, parents = [], []
    for k, s in enumerate(sigs):
        count = block_count(s)
        for b in range(count):
            out.append(s.block(b, count))
            lo, hi = s.block_rows(b, count)
            parents.append((first + k, slice(lo, hi)))
    return out, parents
