"""Several effects at once: forward selection over the catalogue.

Round `k` tests every candidate not yet chosen, added to the effects chosen so far, with the
cross-fitted evidence of `_significance.py`. A candidate passes when its one-sided p value is
below `alpha / m` (`m`: the candidates still in play, so the family-wise false-alarm rate over
the round stays at `alpha`) and its typical held-out gain reaches `min_gain`; of those that
pass, the one with the largest held-out gain is added. Selection stops when none passes. Once
an effect is in, a correlated candidate that only echoed it loses its gain, so it is not named
twice; a second, different effect keeps its own and is added next.

Every family's size is chosen inside the fitting flights (`Effect.sized`), so the round
compares the candidates by held-out gain alone: none is preferred, held back or given a
higher bar for its kind.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence

from ._attribution import Engine, Model
from ._catalogue import Effect
from ._significance import Evidence, Half, evidence

#: Family-wise false-alarm level per round: the 5 % the false alarms may cost. The test is
#: conservative (a candidate that explains nothing only adds held-out error), so the level is
#: an upper bound, not the rate (`benchmarks/results/diagnosis_power_*.md`: false alarms).
ALPHA = 0.05
#: Smallest typical relative drop of a block's held-out error that counts (2 %).
MIN_GAIN = 0.02
#: Most effects selected.
MAX_EFFECTS = 3
@dataclasses.dataclass
class Selection:
    """`chosen`: the effects in the order added with the evidence that admitted each;
    `models`: the chosen model on each half;
    `rounds`: per round, its per-candidate level, every candidate's evidence and the effect
    it added (`None` for the round that stopped).
    Derived from them: `first`, every candidate's evidence in the first round (each against
    the baseline alone); `last`, every candidate's evidence in the last round it was tested
    (for those chosen, the round that admitted it); `level`, the per-candidate level of that
    round."""

    chosen: list[tuple[Effect, Evidence]]
    models: list[Model]
    rounds: list[tuple[float, dict[str, Evidence], str | None]]

    @functools.cached_property
    def first(self) -> dict[str, Evidence]:
        return dict(self.rounds[0][1]) if self.rounds else {}

    @functools.cached_property
    def last(self) -> dict[str, Evidence]:
        return {k: ev for _, evs, _ in self.rounds for k, ev in evs.items()}

    @functools.cached_property
    def level(self) -> dict[str, float]:
        return {k: lv for lv, evs, _ in self.rounds for k in evs}


def passes(ev: Evidence, level: float, min_gain: float) -> bool:
    """Does a candidate with evidence `ev` pass a round at `level`?"""
    return ev.p < level and ev.gain >= min_gain


def forward_select(engine: Engine, halves: list[Half], catalogue: Sequence[Effect],
                   alpha: float = ALPHA, min_gain: float = MIN_GAIN,
                   max_effects: int = MAX_EFFECTS,
                   on_first: Callable[[Effect], None] | None = None) -> Selection:
    """Forward selection over `catalogue` (see the module docstring); `on_first(effect)` is
    called with the first round's leader as soon as it is chosen (the diagnosis starts the
    augmented model's fit for it then, beside the later rounds)."""
    models: list[Model] = [() for _ in halves]
    remaining = list(catalogue)
    chosen, rounds = [], []
    while remaining and len(chosen) < max_effects:
        lv = alpha / len(remaining)
        ev = {e.name: evidence(engine, halves, models, e) for e in remaining}
        ok = [e for e in remaining if passes(ev[e.name], lv, min_gain)]
        if not ok:
            rounds.append((lv, ev, None))
            break
        best = max(ok, key=lambda e: ev[e.name].mean)
        rounds.append((lv, ev, best.name))
        chosen.append((best, ev[best.name]))
        if on_first is not None and len(chosen) == 1:
            on_first(best)
        models = [m + ((best, v),) for m, v in zip(models, ev[best.name].variants)]
        remaining.remove(best)
    return Selection(chosen, models, rounds)
