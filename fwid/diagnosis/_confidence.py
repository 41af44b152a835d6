"""A confidence set of explanations: every model of the gap the held-out blocks cannot reject.

The explanations are the baseline alone (`none`), each catalogue entry and probe alone, the
pairs of the catalogue entries that gain most alone (`PAIR_POOL`; ordered by that gain), and
the effects the forward selection chose together, up to its first probe (an entry after a
probe only echoes it). Every entry is a family whose size was chosen inside the fitting
flights, so each pairs with every other on the same terms. The best explanation gives the
verdict (its first effect). Each is scored, as the selection's evidence is
(`_significance.py`), by the cross-fit: on every scoring block of about a second, the model
fitted on the other flights gives, per band, the held-out sum of squares pooled over the
loads (each scaled by the baseline's training mean square `s_l`), and the block's loss is

    L_j(m) = sum_band log( sum_l SSE_j,l,band(m) / s_l ),

so that the loss difference of a single effect and the baseline is the selection's `d_j`
exactly. A model that explains nothing only adds held-out error, so over-fitting costs a
larger explanation instead of helping it.

Each effect of an explanation is charged the smallest held-out gain that counts,
`-log(1 - g)` per block, with `g` the selection's `MIN_GAIN` (2 %): the set compares
explanations by the loss they would have if each effect had to earn that gain (an interval
null: "at least 2 % better", not "better"). Without the charge, an effect that fits a
fraction of a per cent of the loads' noise significantly over tens of blocks would be
preferred to `none`.

The set is Hansen, Lunde & Nason's *model confidence set* (Econometrica 79, 2011, 453-497)
with their `T_max` statistic: while the live models differ significantly (the largest
standardised excess loss over the live models' mean is compared with its bootstrap
distribution), the worst is eliminated; each model's MCS p value is the largest elimination
p value up to its own. The set at level `LEVEL` keeps the models whose p value reaches it: with
probability at least `1 - LEVEL` (asymptotically) it holds the best explanation. The bootstrap
resamples whole scoring blocks (a block bootstrap of the samples with one-second blocks): the
residual's colour stays inside a block, and given the fit, blocks are taken as independent, as
the selection's t test does.

The set answers "which explanations could be the best", and a larger explanation that holds
a kept smaller one and fits the blocks about as well could always be: it is kept by the MCS
even when its extra effects earn nothing, because the best of many nested models is one of
them by chance. The set is therefore made parsimonious (`parsimonious`): an explanation is
dropped when it holds a kept smaller one (`none` is held by all) and is not significantly
better than it, by the one-sided block-bootstrap test of the mean charged loss difference at
the same `LEVEL`. Every effect of a kept explanation has then earned its place against the
explanations without it, and a pair is reported only when the flights show both effects.
No setting is added: the test, its level and its bootstrap are the set's own.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence

import numpy as np

from ._attribution import Engine, Model
from ._catalogue import Effect
from ._selection import MIN_GAIN
from ._significance import Evidence, Half, evidence

#: Level of the set: an explanation is kept when its MCS p value is at least this.
LEVEL = 0.10
#: Bootstrap resamples of the blocks.
RESAMPLES = 2000
#: Pairs are formed from this many catalogue entries, those with the largest held-out gain
#: alone (a positive one): a pair both of whose members explain
#: nothing alone is not tried.
PAIR_POOL = 4


@dataclasses.dataclass
class Explanation:
    """One model of the gap: its effects (catalogue entries or probes, in order of their gain
    alone), its per-block held-out loss (`loss`, over every half's scoring blocks) and, once
    the set is built, its MCS p value."""

    effects: tuple[Effect, ...]
    loss: np.ndarray
    p_value: float = 1.0

    @property
    def names(self) -> list[str]:
        return [e.name for e in self.effects]

    @property
    def charge(self) -> float:
        """Per block, the smallest gains its effects must earn (module docstring)."""
        return float(-np.log1p(-MIN_GAIN) * len(self.effects))

    @property
    def mean_loss(self) -> float:
        """The mean block loss with the charge."""
        return float(np.mean(self.loss)) + self.charge


def bootstrap_weights(n: int, resamples: int = RESAMPLES, seed: int = 0) -> np.ndarray:
    """`(resamples, n)` weights of the `n` blocks in each bootstrap draw (with replacement):
    a draw's mean of per-block values is `weights @ values`. The seed makes the set
    reproducible."""
    rng = np.random.default_rng(seed)
    return rng.multinomial(n, np.full(n, 1.0 / n), size=resamples) / n


def mcs_p_values(losses: np.ndarray, resamples: int = RESAMPLES, seed: int = 0) -> np.ndarray:
    """The MCS p value of each model (Hansen, Lunde & Nason 2011, `T_max`).

    **Arguments:** `losses`, shape `(blocks, models)`; `resamples` (bootstrap draws of the
    blocks, with replacement); `seed` (of the draws: the set is reproducible).

    **Returns:** the p values, shape `(models,)`; the last model standing has 1.
    """
    n, m = losses.shape
    counts = bootstrap_weights(n, resamples, seed)
    live = list(range(m))
    out = np.ones(m)
    worst_p = 0.0
    while len(live) > 1:
        excess = losses[:, live] - losses[:, live].mean(axis=1, keepdims=True)
        mean = excess.mean(axis=0)
        boot = counts @ excess - mean  # (B, k): centred bootstrap means
        sd = np.sqrt(np.mean(boot ** 2, axis=0))
        safe = np.where(sd > 0, sd, np.inf)
        t = np.where(sd > 0, mean / safe, 0.0)
        t_boot = np.max(boot / safe, axis=1)
        worst_p = max(worst_p, float(np.mean(t_boot >= t.max())))
        k = int(np.argmax(t))
        out[live[k]] = worst_p
        live.pop(k)
    return out


def _block_losses(engine: Engine, halves: Sequence[Half], models: Sequence[Model],
                  cache: dict) -> np.ndarray:
    """Per scoring block (over every half), the loss of the module docstring of `models`
    (one per half)."""
    out = []
    for h, (half, model) in enumerate(zip(halves, models)):
        total = np.zeros(len(half.score))
        for band in ("averaged", "flapping"):
            acting = tuple((e.name, v) for e, v in model if e.band == band)
            key = (h, band, acting)
            if key not in cache:
                chans = engine.channels(band)
                w = np.array([1.0 / half.sigma2[ch] for ch in chans])
                err = engine.block_errors(half.fit, half.score,
                                          tuple((e, v) for e, v in model if e.band == band),
                                          band)
                cache[key] = np.log(np.maximum(err @ w, 1e-300))
            total += cache[key]
        out.append(total)
    return np.concatenate(out)


def explanations(engine: Engine, halves: Sequence[Half], first: dict[str, Evidence],
                 candidates: Sequence[Effect], chosen: Sequence[Effect] = (),
                 pair_pool: int = PAIR_POOL) -> list[Explanation]:
    """The explanations of the module docstring with their block losses.

    **Arguments:** `engine`, `halves` (the cross-fit's), `first` (every candidate's evidence
    against the baseline alone: its variants per half and its gain), `candidates` (catalogue
    entries and probes), `chosen` (the forward selection's effects, in order), `pair_pool`.

    **Returns:** the explanations, `none` first, then the single ones, the pairs and the
    selection's model up to its first probe; one whose losses equal an earlier one's (a
    second effect that acts on no load) is left out.
    """
    cache: dict = {}
    base = Explanation((), _block_losses(engine, halves, [() for _ in halves], cache))
    out = [base]
    for e in candidates:
        models = [((e, v),) for v in first[e.name].variants]
        out.append(Explanation((e,), _block_losses(engine, halves, models, cache)))
    gaining = sorted((e for e in candidates if not e.probe
                      and first[e.name].mean > 0), key=lambda e: -first[e.name].mean)[:pair_pool]
    groups = [tuple(p) for p in itertools.combinations(gaining, 2)]
    # the selection's effects up to its first probe: an entry after a probe only echoes it
    # (`_scores.Scores.named` reports it so, under `unexplained`)
    upto = next((k + 1 for k, e in enumerate(chosen) if e.probe), len(chosen))
    chosen = tuple(chosen)[:upto]
    if len(chosen) > 1 and chosen not in groups:
        groups.append(chosen)
    for group in groups:
        models = []
        for half, v in zip(halves, first[group[0].name].variants):
            model = ((group[0], v),)
            for e in group[1:]:
                model = model + ((e, engine.choose(half.fit, model, e, half.sigma2)),)
            models.append(model)
        out.append(Explanation(group, _block_losses(engine, halves, models, cache)))
    kept: list[Explanation] = []
    for x in out:
        if not any(np.array_equal(x.loss, k.loss) for k in kept):
            kept.append(x)
    return kept


def better_p_value(larger: np.ndarray, smaller: np.ndarray, resamples: int = RESAMPLES,
                   seed: int = 0, weights: np.ndarray | None = None) -> float:
    """The one-sided block-bootstrap p value of "`larger` is no better than `smaller`": the
    share of centred bootstrap means of the per-block difference `larger - smaller` (charged
    losses) at or below its observed mean. Small when the larger explanation's loss is
    significantly lower. `weights`: `bootstrap_weights` drawn once for many tests (default:
    drawn here from `resamples`, `seed`)."""
    d = np.asarray(larger, dtype=float) - np.asarray(smaller, dtype=float)
    w = bootstrap_weights(d.size, resamples, seed) if weights is None else weights
    boot = w @ (d - d.mean())
    return float(np.mean(boot <= d.mean()))


def parsimonious(kept: Sequence[Explanation], level: float = LEVEL,
                 resamples: int = RESAMPLES) -> list[Explanation]:
    """`kept` without every explanation that holds a kept smaller one and is not
    significantly better than it (`better_p_value` at `level`; module docstring), in the
    order of `kept`. Smaller explanations are judged first, so each is compared only with
    explanations that stay."""
    stays: list[Explanation] = []
    weights = bootstrap_weights(len(kept[0].loss), resamples) if kept else None
    for x in sorted(kept, key=lambda x: len(x.effects)):
        own = set(x.names)
        subs = [y for y in stays if set(y.names) < own]
        if all(better_p_value(x.loss + x.charge, y.loss + y.charge, weights=weights) < level
               for y in subs):
            stays.append(x)
    return [x for x in kept if any(x is y for y in stays)]


def confidence_set(found: list[Explanation], level: float = LEVEL,
                   resamples: int = RESAMPLES) -> list[Explanation]:
    """The explanations whose MCS p value is at least `level`, made `parsimonious`, best
    (least mean held-out loss) first; every explanation's `p_value` is set."""
    p = mcs_p_values(np.stack([x.loss + x.charge for x in found], axis=1), resamples)
    for x, pv in zip(found, p):
        x.p_value = float(pv)
    kept = sorted((x for x in found if x.p_value >= level), key=lambda x: x.mean_loss)
    return parsimonious(kept, level, resamples)


def as_rows(kept: Sequence[Explanation], base: Explanation) -> list[dict]:
    """`diagnosis.json`'s `confidence_set`: per explanation its effects (`[]`: none), its
    mean held-out block loss relative to the baseline's `base` (`loss`: the mean over blocks
    of `L_j(m) - L_j(none)`, negative when it explains part of the gap; `gain_pct`, the
    typical held-out error drop `100 (1 - exp(loss))`), the `charge` its effects had to
    earn (the set compares `loss + charge`) and its MCS p value."""
    out = []
    for x in kept:
        loss = float(np.mean(x.loss - base.loss))
        out.append({"explanation": x.names, "loss": loss,
                    "gain_pct": 100.0 * (1.0 - float(np.exp(loss))), "charge": x.charge,
                    "p_value": x.p_value})
    return out


def sequential(engine: Engine, halves: Sequence[Half], first: dict[str, Evidence],
               effects: Sequence[Effect]) -> list[tuple[Effect, Evidence]]:
    """The evidence of an explanation's `effects` as forward selection would have admitted
    them in that order: the first's against the baseline (`first`), each further one's
    added to those before it (`_significance.evidence`), for the rows of `diagnosis.json`."""
    out: list[tuple[Effect, Evidence]] = []
    models = [() for _ in halves]
    for e in effects:
        ev = first[e.name] if not out else evidence(engine, list(halves), models, e)
        out.append((e, ev))
        models = [m + ((e, v),) for m, v in zip(models, ev.variants)]
    return out


def rivals(rows: Sequence[dict], named: Sequence[str]) -> list[str]:
    """The distinct first effects among `named` (the catalogue's) of the kept explanations
    `rows` (`as_rows`, best first): two or more when the flights cannot tell catalogue
    effects apart, the case a discriminating input is for (`fwid design --discriminate`)."""
    out: list[str] = []
    for row in rows:
        first = next((e for e in row["explanation"] if e in named), None)
        if first is not None and first not in out:
            out.append(first)
    return out


def next_flight(rows: Sequence[dict], named: Sequence[str]) -> dict | None:
    """When the kept explanations `rows` are led by different catalogue effects (`rivals`),
    the flight that would tell the first two apart: `{"tell_apart": [X, Y], "how": ...}`
    (`fwid design --discriminate`); `None` otherwise."""
    pair = rivals(rows, named)[:2]
    if len(pair) < 2:
        return None
    return {"tell_apart": pair,
            "how": f"these flights cannot tell {pair[0]} from {pair[1]}: fly the input of "
                   "`fwid design --discriminate DIAGNOSIS_DIR` (the manoeuvre over which the "
                   "two augmented models' predictions differ most), then diagnose again with "
                   "that flight among the test flights"}
