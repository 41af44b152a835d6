"""The least-squares engine of the attribution: the baseline and any set of catalogue effects,
fitted to the loads of some flights and scored on others.

A *model* is a tuple of `(Effect, variant)` pairs added to the paper's baseline (Eqs. 2-6 below
the split, Eq. 12 above it). A *channel* is a `(load, band)` pair; each is fitted on its own,
with the regressors of the effects that act in its band. A *unit* is a flight or a block of
one: its trim load and flapping Fourier coefficients are its own (`_regression.py`).

An effect acts on the loads where it predicts flights it was not fitted to: its variant is
wrapped in `OnLoads` with those loads, chosen by leave-one-flight-out cross-validation on the
fitting flights (`Engine.choose`). An effect that is real on one load (a moment that grows
with the incidence squared) is then not charged, in the held-out test, for the noise its
columns fit on the loads it does not touch. An effect that replaces the deflection
(`Effect.replaces_input`) acts on every load: it is one change of the one deflection, with no
column to over-fit.

The loads of the axis that was not manoeuvred (the lateral ones in a longitudinal diagnosis)
take only the effects whose columns there carry the manoeuvre or belong to neither axis
(`Effect.crosses_axes`: the coupling, the flapping modulated by every state, the flapping
frequency, a drift; `Engine.allowed`). That axis's own states, attitude and control barely
move, so columns built from them fit only what their noise hides from the baseline (the
attitude probe on L, through a roll angle that hardly moves, would make clean longitudinal
flights `unexplained`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ._catalogue import CATALOGUE, Effect, axis_of, base_columns
from ._regression import (Projector, error, harmonic_series, local_design,
                          normal_equations, residual, solve, solve_stack)
from ._signals import Signals

Model = tuple  # of (Effect, variant) pairs


@dataclasses.dataclass(frozen=True)
class OnLoads:
    """A variant of an effect that acts on `loads` only (`Engine.choose`)."""

    variant: object
    loads: tuple[str, ...]


def unwrap(variant):
    """The effect's own variant (a time constant, ...), without the loads it acts on."""
    return variant.variant if isinstance(variant, OnLoads) else variant


def acts_on(variant, load: str) -> bool:
    return not isinstance(variant, OnLoads) or load in variant.loads


@dataclasses.dataclass
class Unit:
    """A flight, or rows `rows` of the flight unit `parent` (a block): a block's regressors
    are its flight's, sliced (a lagged deflection or a flapping series is computed on the
    whole flight), its local terms its own."""

    signals: Signals
    local: dict[str, np.ndarray]  # by band
    projector: dict[str, Projector]  # by band
    parent: int | None = None
    rows: slice | None = None


def units(sigs: Sequence[Signals], parents: Sequence[tuple[int, slice]] | None = None
          ) -> list[Unit]:
    """Local designs: a constant below the split, the Fourier series of Eq. (12) above it.
    `parents`, if given, is each signal's `(parent unit, rows)`."""
    out = []
    for k, s in enumerate(sigs):
        local = {"averaged": np.ones((s.n, 1)), "flapping": local_design(s.phase)}
        parent, rows = parents[k] if parents is not None else (None, None)
        out.append(Unit(s, local, {b: Projector(m) for b, m in local.items()}, parent, rows))
    return out


def acting(model: Model, channel) -> Model:
    """The entries of `model` that act on `channel` (its band, its load), variants unwrapped."""
    load, band = channel
    return tuple((e, unwrap(v)) for e, v in model if e.band == band and acts_on(v, load))


#: Costs within this relative distance of the least are a tie (`simplest_best`): members that
#: act identically on the data differ only by rounding.
TIE_RTOL = 1e-9


def simplest_best(costs) -> int:
    """Index of the least of `costs`, the first of those that tie with it (`TIE_RTOL`)."""
    least = min(costs)
    return next(k for k, c in enumerate(costs) if c <= least + TIE_RTOL * abs(least))


def numbers_of(variant) -> int:
    """How many numbers a member of a family is chosen with beyond its columns: a filter's
    time constants, limits and sizes (`("rate-limit", tau, rmax)`: 2); none for a member
    that is a set of columns (a spline's components, a modulation)."""
    if isinstance(variant, tuple):
        return sum(isinstance(x, (int, float)) for x in variant)
    return 0


def one_standard_error(errors: Sequence[np.ndarray], sizes: Sequence[int]) -> int:
    """The member a leave-one-out comparison picks by the one-standard-error rule (Breiman
    et al. 1984; Hastie, Tibshirani & Friedman, Sec. 7.10): `errors[k]` are member `k`'s
    errors on each left-out unit, `sizes[k]` its size (its columns and the numbers it is
    chosen with, `numbers_of`). Of the members whose
    total error is within one standard error of the least (that of the best member's total,
    from the spread of its units' errors), the smallest; among those, the least
    error (`simplest_best`). The least of many leave-one-out errors is biased low, and a
    larger member that wins by less than its own noise would fit more of it; members of one
    size are compared by their error alone."""
    costs = [float(np.sum(e)) for e in errors]
    best = simplest_best(costs)
    n = len(errors[best])
    se = float(np.std(errors[best], ddof=1) * np.sqrt(n)) if n > 1 else 0.0
    within = [k for k, c in enumerate(costs) if c <= costs[best] + se]
    fewest = min(sizes[k] for k in within)
    keep = [k for k in within if sizes[k] == fewest]
    return keep[simplest_best([costs[k] for k in keep])]


class Engine:
    """Fits the baseline plus any model of `catalogue` effects to the `loads` of some units and
    scores it on others. Designs, units' normal equations and fits are cached, so forward selection
    and the folds of the cross-fit reuse each other's work."""

    def __init__(self, all_units: Sequence[Unit], loads: Sequence[str], catalogue=CATALOGUE,
                 own: Sequence[str] | None = None, cutoff: float = 5.0):
        self.units = list(all_units)
        self.loads = tuple(loads)
        #: The loads of the manoeuvred axis (default: all).
        self.own = self.loads if own is None else tuple(ld for ld in self.loads if ld in own)
        self.catalogue = tuple(catalogue)
        #: The split [Hz] of the units' signals (Section III.B).
        self.cutoff = cutoff
        self._design: dict = {}
        self._series: dict = {}
        self._fits: dict = {}
        self._normal: dict = {}
        self._loo: dict = {}
        self._acting: dict = {}
        self._made: dict = {}

    def made(self, key, make):
        """`make()` the first time `key` is asked for, its value after: what the families'
        `bind` derive from the units (the spline bases both `nonlinear-aero` and
        `flap-coupling` read, made once, so they also share one evaluation per signal)."""
        if key not in self._made:
            self._made[key] = make()
        return self._made[key]

    def channels(self, band: str) -> list[tuple[str, str]]:
        return [(ld, band) for ld in self.loads]

    def allowed(self, effect: Effect) -> tuple[str, ...]:
        """The loads `effect` may act on: the manoeuvred axis's (`own`), and the other axis's
        too when its columns there carry the manoeuvre (`Effect.crosses_axes`)."""
        return self.loads if effect.crosses_axes else self.own

    def series(self, i: int, load: str) -> tuple[np.ndarray, np.ndarray]:
        """Unit `i`'s own flapping series of `load` (Eq. 12 fitted to it) and its phase
        derivative: what `flap-coupling` modulates."""
        if (i, load) not in self._series:
            u = self.units[i]
            coef = u.projector["flapping"].coefficients(u.local["flapping"],
                                                        self.target(i, (load, "flapping")))
            self._series[(i, load)] = harmonic_series(u.signals.phase, coef)
        return self._series[(i, load)]

    def design(self, i: int, channel, model: Model = ()) -> np.ndarray:
        """Unit `i`'s global regressors of `channel` under `model`: the baseline's, the acting
        deflection of an effect that `replaces_input` in place of the measured one, then the
        other effects' columns."""
        load, band = channel
        model = acting(model, channel)
        key = (i, channel, tuple((e.name, v) for e, v in model))
        if key not in self._design and self.units[i].parent is not None:
            u = self.units[i]
            self._design[key] = self.design(u.parent, channel, model)[u.rows]
        if key not in self._design:
            s = self.units[i].signals
            g = base_columns(s, load, band)
            h, dh = self.series(i, load) if model else (None, None)
            extra = []
            for e, v in model:
                if e.replaces_input:  # the control is the last base column; the acting
                    # deflection is the same for every load of the axis: made once
                    key_in = (i, e.name, v, axis_of(load))
                    if key_in not in self._acting and e.all_columns and v in e.variants:
                        cols = e.all_columns(s, load, e.variants)
                        for k, w in enumerate(e.variants):
                            self._acting[(i, e.name, w, axis_of(load))] = cols[:, k:k + 1]
                    if key_in not in self._acting:
                        self._acting[key_in] = e.columns(s, load, v, h, dh)
                    g = np.concatenate([g[:, :-1], self._acting[key_in]], axis=1)
                else:
                    extra.append(e.columns(s, load, v, h, dh))
            self._design[key] = np.concatenate([g] + extra, axis=1) if extra else g
        return self._design[key]

    def target(self, i: int, channel) -> np.ndarray:
        load, band = channel
        return self.units[i].signals.loads[band][load]

    def n_samples(self, idx) -> int:
        return sum(self.units[i].signals.n for i in idx)

    def fit(self, idx: Sequence[int], channel, model: Model = ()):
        """Global coefficients on units `idx`: `(theta, sse)` (the training error)."""
        model = acting(model, channel)
        key = (tuple(idx), channel, tuple((e.name, v) for e, v in model))
        if key not in self._fits:
            self._fits[key] = solve([self.normal_equations(i, channel, model) for i in idx])
        return self._fits[key]

    def normal_equations(self, i: int, channel, model: Model = ()):
        """Unit `i`'s share of the normal equations of `channel` under `model` (cached: the
        folds of the cross-fit share their units)."""
        model = acting(model, channel)
        key = (i, channel, tuple((e.name, v) for e, v in model))
        if key not in self._normal:
            self._normal[key] = normal_equations(self.design(i, channel, model),
                                                 self.target(i, channel),
                                                 self.units[i].projector[channel[1]])
        return self._normal[key]

    def residual(self, i: int, channel, theta, model: Model = ()) -> np.ndarray:
        """Unit `i`'s residual with the global `theta`, its local terms re-estimated."""
        return residual(self.design(i, channel, model), self.target(i, channel),
                        self.units[i].projector[channel[1]], theta)

    def mean_square(self, idx, model: Model = ()) -> dict:
        """Training mean-square error per channel (both bands) of `model` on units `idx`."""
        n = self.n_samples(idx)
        return {ch: max(self.fit(idx, ch, model)[1] / n, 1e-300)
                for band in ("averaged", "flapping") for ch in self.channels(band)}

    def best_variant(self, idx, model: Model, effect: Effect, sigma2: dict, loads=None):
        """The variant of `effect` (added to `model`) with the least training error on units
        `idx`, summed over the channels of its band it acts on (`loads`; default: those it
        is `allowed` on), each scaled by `sigma2` (the baseline's); for an effect whose
        variants differ in size (`Effect.sized`), the least leave-one-unit-out error instead
        (with fewer than three units, the training error). Of members that tie, the first
        (the variants are listed simplest first): a rate limit that never binds is a plain
        lag, and must not be reported as a rate limit. Members of different sizes are
        weighed by the one-standard-error rule (`one_standard_error`); a family that can
        `refine` its chosen member then tries the members near it the same way."""
        if len(effect.variants) == 1:
            return effect.variants[0]
        chans = [ch for ch in self.channels(effect.band) if ch[0] in self.allowed(effect)
                 and (loads is None or ch[0] in loads)]
        if effect.sized and len(idx) >= 3:
            def pick(variants):
                loo = [[self.loo_errors(idx, ch, model + ((effect, v),)) for ch in chans]
                       for v in variants]
                return variants[one_standard_error(
                    [sum(e / sigma2[ch] for (e, _), ch in zip(m, chans)) for m in loo],
                    [sum(k for _, k in m) + numbers_of(v) for m, v in zip(loo, variants)])]

            best = pick(effect.variants)
            near = tuple(v for v in effect.refine(best) if v != best) if effect.refine else ()
            return pick((best,) + near) if near else best
        costs = [sum(self.fit(idx, ch, model + ((effect, v),))[1] / sigma2[ch]
                     for ch in chans) for v in effect.variants]
        return effect.variants[simplest_best(costs)]

    def lowers(self, idx, model: Model, effect: Effect, channel, variant=None) -> bool:
        """Does `effect` (added to `model`) lower the leave-one-unit-out error of `channel`
        over the units `idx`? With `variant`, that member's error below the model's. Else
        (a family whose members differ in size, `Effect.sized`), by the one-standard-error
        rule with the model without it as the family's empty member (`one_standard_error`):
        the least of many members' leave-one-out errors is biased low, so a member must beat
        the model without it by more than the noise of that comparison, and a larger one by
        more than a smaller."""
        base = self.loo_errors(idx, channel, model)
        if variant is not None:
            return (float(np.sum(self.loo_errors(idx, channel, model + ((effect, variant),))[0]))
                    < float(np.sum(base[0])))
        loo = [self.loo_errors(idx, channel, model + ((effect, v),)) for v in effect.variants]
        return one_standard_error([base[0]] + [e for e, _ in loo],
                                  [base[1]] + [k + numbers_of(v) for (_, k), v
                                               in zip(loo, effect.variants)]) != 0

    def choose(self, idx, model: Model, effect: Effect, sigma2: dict) -> OnLoads:
        """`effect`'s loads and variant. The loads: those of its band whose
        leave-one-flight-out error over the units `idx` (each flight scored by the model
        fitted on the others, its local terms its own) it lowers (`lowers`). No threshold
        beyond the noise of that comparison: a column set that only fits noise raises that
        error. Every load for an effect that replaces the deflection, or with fewer than
        three units. Only the loads it is `allowed` on. The variant (`best_variant`): for a
        family whose members differ in size, chosen on those loads only, among the members
        that lower the error of each of them (`on_loads`), so the member explains what the
        family was found to act on, not the noise of the loads it does not touch."""
        chans = [ch for ch in self.channels(effect.band) if ch[0] in self.allowed(effect)]
        every = tuple(ld for ld, _ in chans)
        if len(idx) < 3 or effect.replaces_input:
            return OnLoads(self.best_variant(idx, model, effect, sigma2), every)
        if not effect.sized:
            v = self.best_variant(idx, model, effect, sigma2)
            return OnLoads(v, tuple(ch[0] for ch in chans
                                    if self.lowers(idx, model, effect, ch, OnLoads(v, every))))
        loads = tuple(ch[0] for ch in chans if self.lowers(idx, model, effect, ch))
        return self.on_loads(idx, model, effect, sigma2, loads)

    def on_loads(self, idx, model: Model, effect: Effect, sigma2: dict, loads) -> OnLoads:
        """`effect` acting on `loads`, its member (`best_variant` on those loads) among those
        that lower the leave-one-unit-out error over the units `idx` of each of them
        (`lowers`; all members when none does). With no load, it acts on none (the member
        over every load it is allowed on, for the record)."""
        if not loads:
            return OnLoads(self.best_variant(idx, model, effect, sigma2), ())
        fits = tuple(v for v in effect.variants
                     if all(self.lowers(idx, model, effect, (ld, effect.band), v)
                            for ld in loads))
        family = dataclasses.replace(effect, variants=fits) if fits else effect
        return OnLoads(self.best_variant(idx, model, family, sigma2, loads), tuple(loads))

    def loo_error(self, idx, channel, model: Model) -> float:
        """Leave-one-unit-out error of `channel` over the units `idx`: the sum of
        `loo_errors`."""
        return float(np.sum(self.loo_errors(idx, channel, model)[0]))

    def loo_errors(self, idx, channel, model: Model) -> tuple[np.ndarray, int]:
        """Each unit's sum of squares of `channel` under the fit to the other units of `idx`,
        from the units' normal equations, and the number of columns fitted (cached: every
        candidate of a round compares with the same model without it)."""
        key = (tuple(idx), channel, tuple((e.name, v) for e, v in acting(model, channel)))
        if key not in self._loo:
            parts = [self.normal_equations(i, channel, model) for i in idx]
            A, b, c = (np.stack([p[j] for p in parts]) for j in range(3))
            th = solve_stack(A.sum(0) - A, b.sum(0) - b)  # each unit left out in turn
            self._loo[key] = (error((A, b, c), th), A.shape[-1])
        return self._loo[key]

    def block_errors(self, fit_idx, score_idx, model: Model, band: str) -> np.ndarray:
        """Sum of squared residuals of `model` fitted on `fit_idx`, on each unit of `score_idx`
        and channel of `band`: shape `(len(score_idx), len(loads))`."""
        out = np.empty((len(score_idx), len(self.loads)))
        for c, ch in enumerate(self.channels(band)):
            th, _ = self.fit(fit_idx, ch, model)
            for j, i in enumerate(score_idx):
                out[j, c] = float(np.sum(self.residual(i, ch, th, model) ** 2))
        return out
