"""Which effect: fit each candidate on the training flights, test it out of sample, rank.

Significance is judged by cross-validation over whole flights (or, with fewer than
`MIN_FOLDS` training flights, contiguous blocks of them): each fold's model is fitted on the
other folds and scored on the held-out one, for the baseline and for every candidate. The
per-fold log ratios of the held-out mean-square errors are independent across flights, so the
test stays valid when the residuals within a flight are coloured (they always are, Morelli &
Klein 1995), and over-fitting costs a candidate out of sample instead of being rewarded. A
candidate is significant for a load when the mean log ratio is positive by a one-sided t test at
level `ALPHA` divided by the number of (candidate, load) pairs tried (Bonferroni), and the
held-out error drops by at least `MIN_GAIN`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from scipy import stats

from ._catalogue import CATALOGUE, Effect, base_columns
from ._regression import Projector, harmonic_series, local_design, residual, solve
from ._signals import BANDS, Signals

#: Family-wise false-alarm level of the significance test.
ALPHA = 0.01
#: Smallest relative drop of the held-out mean-square error that counts (2 %).
MIN_GAIN = 0.02
#: Fewest cross-validation folds; fewer training flights are cut into blocks.
MIN_FOLDS = 8


@dataclasses.dataclass
class _Unit:
    signals: Signals
    local: dict[str, np.ndarray]  # by band
    projector: dict[str, Projector]  # by band


def units(sigs: Sequence[Signals]) -> list[_Unit]:
    """Local designs: a constant below the split, the Fourier series of Eq. (12) above it."""
    out = []
    for s in sigs:
        local = {"averaged": np.ones((s.n, 1)), "flapping": local_design(s.phase)}
        out.append(_Unit(s, local, {b: Projector(m) for b, m in local.items()}))
    return out


class Engine:
    """Fits the baseline and the candidates of `catalogue` to the loads of some flights.

    A *channel* is a `(load, band)` pair; each is fitted on its own.
    """

    def __init__(self, all_units: Sequence[_Unit], loads: Sequence[str], catalogue=CATALOGUE):
        self.units = list(all_units)
        self.loads = tuple(loads)
        self.catalogue = tuple(catalogue)
        self._cache: dict = {}
        self._series: dict = {}

    def channels(self, band: str) -> list[tuple[str, str]]:
        return [(ld, band) for ld in self.loads]

    def series(self, i: int, load: str) -> tuple[np.ndarray, np.ndarray]:
        """Unit `i`'s own flapping series of `load` (Eq. 12 fitted to it) and its phase
        derivative: what `flap-coupling` modulates."""
        if (i, load) not in self._series:
            u = self.units[i]
            coef = u.projector["flapping"].coefficients(u.local["flapping"],
                                                        self.target(i, (load, "flapping")))
            self._series[(i, load)] = harmonic_series(u.signals.phase, coef)
        return self._series[(i, load)]

    def design(self, i, channel, effect: Effect | None = None, variant=None) -> np.ndarray:
        load, band = channel
        key = (i, channel, None if effect is None else effect.name, variant)
        if key not in self._cache:
            s = self.units[i].signals
            if effect is None:
                self._cache[key] = base_columns(s, load, band)
            else:
                h, dh = self.series(i, load)
                extra = effect.columns(s, load, variant, h, dh)
                base = self.design(i, channel)
                if effect.replaces_input:  # the control is the last base column
                    self._cache[key] = np.concatenate([base[:, :-1], extra], axis=1)
                else:
                    self._cache[key] = np.concatenate([base, extra], axis=1)
        return self._cache[key]

    def target(self, i, channel) -> np.ndarray:
        load, band = channel
        return self.units[i].signals.loads[band][load]

    def fit(self, idx, channel, effect=None, variant=None):
        """Global coefficients on units `idx`; returns `(theta, sse)` (training error)."""
        band = channel[1]
        g = [self.design(i, channel, effect, variant) for i in idx]
        y = [self.target(i, channel) for i in idx]
        p = [self.units[i].projector[band] for i in idx]
        return solve(g, y, p)

    def residual(self, i, channel, theta, effect=None, variant=None) -> np.ndarray:
        """Unit `i`'s residual with the global `theta`, its local terms re-estimated."""
        return residual(self.design(i, channel, effect, variant), self.target(i, channel),
                        self.units[i].projector[channel[1]], theta)

    def fit_effect(self, idx, effect, sigma2):
        """Best variant of `effect` on units `idx`: `(variant, {channel: theta})`, the variant
        minimising the training error summed over the effect's channels, each scaled by
        `sigma2` (the baseline's)."""
        best = None
        for v in effect.variants:
            fits = {ch: self.fit(idx, ch, effect, v) for ch in self.channels(effect.band)}
            cost = sum(fits[ch][1] / sigma2[ch] for ch in fits)
            if best is None or cost < best[0]:
                best = (cost, v, {ch: fits[ch][0] for ch in fits})
        return best[1], best[2]


@dataclasses.dataclass
class CrossValidation:
    """Held-out mean-square errors per fold and channel: `base[k][channel]`,
    `candidates[name][k][channel]`."""

    folds: list[str]
    base: list[dict]
    candidates: dict[str, list[dict]]


def cross_validate(engine: Engine, idx: Sequence[int]) -> CrossValidation:
    """Leave-one-unit-out over `idx` for the baseline and each candidate."""
    base, cand = [], {e.name: [] for e in engine.catalogue}
    for k in idx:
        train = [i for i in idx if i != k]
        sigma2, eb = {}, {}
        for band in BANDS:
            for ch in engine.channels(band):
                th, sse = engine.fit(train, ch)
                sigma2[ch] = max(sse, 1e-300)
                eb[ch] = float(np.mean(engine.residual(k, ch, th) ** 2))
        base.append(eb)
        for e in engine.catalogue:
            v, th = engine.fit_effect(train, e, sigma2)
            cand[e.name].append({
                ch: float(np.mean(engine.residual(k, ch, th[ch], e, v) ** 2)) for ch in th
            })
    return CrossValidation([engine.units[k].signals.name for k in idx], base, cand)


@dataclasses.dataclass
class LoadTest:
    """Out-of-sample evidence for one candidate on one load."""

    gain: float  # mean relative drop of the held-out mean-square error
    t: float  # t statistic of the per-fold log ratios
    p: float  # one-sided p value
    folds_better: int

    @property
    def as_dict(self):
        return {"cv_gain_pct": 100 * self.gain, "t": self.t, "p": self.p,
                "folds_better": self.folds_better}


def load_tests(cv: CrossValidation, name: str) -> dict[tuple, LoadTest]:
    """Per channel of candidate `name`: its out-of-sample evidence."""
    out = {}
    n = len(cv.folds)
    for ld in cv.candidates[name][0]:
        before = np.array([f[ld] for f in cv.base])
        after = np.array([f[ld] for f in cv.candidates[name]])
        d = np.log(before / after)
        gain = float(np.mean(1.0 - after / before))
        sd = float(np.std(d, ddof=1)) if n > 1 else math.inf
        t = float(np.mean(d) / (sd / math.sqrt(n))) if sd > 0 else (
            math.inf if np.mean(d) > 0 else -math.inf)
        p = float(stats.t.sf(t, df=max(n - 1, 1)))
        out[ld] = LoadTest(gain, t, p, int(np.sum(d > 0)))
    return out


def significant_loads(tests: dict[str, LoadTest], n_tests: int, alpha=ALPHA, min_gain=MIN_GAIN):
    """Loads on which the candidate passes the Bonferroni-corrected test and the gain bar."""
    return [ld for ld, tt in tests.items() if tt.p < alpha / n_tests and tt.gain >= min_gain]
