"""Several effects at once: forward selection over the catalogue.

Round `k` tests every candidate not yet chosen, added to the effects chosen so far, with the
cross-fitted evidence of `_significance.py`. A candidate passes when its one-sided p value is
below `alpha / m` (`m`: the candidates still in play, so the family-wise false-alarm rate over
the round stays at `alpha`) and its typical held-out gain reaches `min_gain`; of those that
pass, the one with the largest held-out gain is added. Selection stops when none passes. Once
an effect is in, a correlated candidate that only echoed it loses its gain, so it is not named
twice; a second, different effect keeps its own and is added next.

An entry built on states' rates (`Effect.rates`: `unsteady-aero`) is the last resort: the
rate of one state carries the load it is reconstructed from (`w' = Z / m + ...`), so such an
entry also "explains" any effect on the other loads of the axis. It gives way to any other
passing catalogue entry that achieves `1 / RATES_MARGIN` of its held-out gain (a real effect
on the loads seen through the other loads' rates is explained less well by the rates than
directly), otherwise it competes with the rest on its gain; and it may enter only as the
first effect: once another effect is in, it picks up that effect's leftover misfit on the
other loads and would name a second effect that is not there. The confidence set
(`_confidence.py`) does not use the margin: it holds the rates' entry alone, beside the other
explanations the held-out blocks cannot reject, which is what the user is told.
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
#: How many times the gain of another passing catalogue entry an entry built on states'
#: rates must have to be preferred to it (chosen on the development half of
#: `benchmarks/diagnosis_power.py`).
RATES_MARGIN = 1.2
#: Smallest typical held-out gain of an entry built on states' rates (3 %): the rates of the
#: other states carry a little of the load's own noise through the kinematic terms
#: (`Z = m (w' - q u0 + ..)`), so such an entry needs more than `MIN_GAIN`.
RATES_MIN_GAIN = 0.03


def _admissible(ok: list[Effect], ev: dict) -> list[Effect]:
    """The passing candidates the round may choose from: an entry built on states' rates
    drops out when another passing catalogue entry (not a probe) has at least
    `1 / RATES_MARGIN` of its gain (module docstring)."""
    rival = max((ev[e.name].mean for e in ok if not e.rates and not e.probe), default=None)
    return [e for e in ok
            if not (e.rates and rival is not None and RATES_MARGIN * rival >= ev[e.name].mean)]


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


def passes(e: Effect, ev: Evidence, level: float, min_gain: float) -> bool:
    """Does candidate `e` with evidence `ev` pass a round at `level`?"""
    return ev.p < level and ev.gain >= (max(min_gain, RATES_MIN_GAIN) if e.rates else min_gain)


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
        if chosen:
            remaining = [e for e in remaining if not e.rates]
            if not remaining:
                break
        lv = alpha / len(remaining)
        ev = {e.name: evidence(engine, halves, models, e) for e in remaining}
        ok = [e for e in remaining if passes(e, ev[e.name], lv, min_gain)]
        if not ok:
            rounds.append((lv, ev, None))
            break
        best = max(_admissible(ok, ev), key=lambda e: ev[e.name].mean)
        rounds.append((lv, ev, best.name))
        chosen.append((best, ev[best.name]))
        if on_first is not None and len(chosen) == 1:
            on_first(best)
        models = [m + ((best, v),) for m, v in zip(models, ev[best.name].variants)]
        remaining.remove(best)
    return Selection(chosen, models, rounds)
