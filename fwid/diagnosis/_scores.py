"""How far the gap shrinks: the baseline and each candidate re-fitted on the training flights
and scored on the test flights, load by load, and the rows of `diagnosis.json` that say so."""

from __future__ import annotations

import math

import numpy as np

from ._attribution import unwrap
from ._campaign import Campaign
from ._catalogue import Effect, filter_text, member_json
from ._disturbance import RED_MIN, colour, spectrum
from ._gapmap import BAND_NAMES, band_energy, rms
from ._heldout import heldout_test
from ._probes import drivers
from ._selection import Selection
from ._signals import BANDS

#: A load is affected by an effect when its held-out gain is at least this share of the
#: largest gain over the loads.
AFFECTED_SHARE = 0.25


def variant_text(v, axis: str = "lon") -> str | None:
    """A family's member in words (`diagnosis.json`'s `variant`)."""
    v = unwrap(v)
    if v is None:
        return None
    if isinstance(v, float):  # a time constant or lead (0: at once)
        return f"{v:g} s" if v else "at once"
    if hasattr(v, "text"):  # a member of a smooth or filtered family
        return v.text(axis)
    return filter_text(v)


class Scores:
    """The test flights' residuals of the baseline (`base`, by channel; `before`, both bands
    summed, by load; `rms_before`) and of any model fitted on the training flights."""

    def __init__(self, c: Campaign, min_gain: float):
        self.c, self.min_gain = c, min_gain
        self.base = self.residuals(())
        self.before = [self.full(r) for r in self.base]
        self.rms_before = self.rms_by_load(self.before)
        #: The test flights' sample steps; the manoeuvred axis's loads' baseline mean squares.
        self.dts = [sig.dt for sig in c.te_sig]
        self.scale = {ld: c.sigma2[(ld, "averaged")] for ld in c.own}
        #: The held-out load residuals after each candidate or probe alone (`row`).
        self.augmented: dict = {}

    def residuals(self, model) -> list[dict]:
        """Per test flight, the residual of `model` fitted on the training flights, by
        channel."""
        c, out = self.c, [{} for _ in self.c.test_idx]
        for band in BANDS:
            for ch in c.engine.channels(band):
                th, _ = c.engine.fit(c.train_idx, ch, model)
                for j, i in enumerate(c.test_idx):
                    out[j][ch] = c.engine.residual(i, ch, th, model)
        return out

    def full(self, res: dict) -> dict:
        return {ld: res[(ld, "averaged")] + res[(ld, "flapping")] for ld in self.c.loads}

    def rms_by_load(self, res_full) -> dict:
        return {ld: rms(np.concatenate([r[ld] for r in res_full])) for ld in self.c.loads}

    @staticmethod
    def shrink(before: dict, after: dict, affected) -> float:
        """The drop [%] of the RMS of the `affected` loads, each relative to its own."""
        ratio = np.mean([(after[ld] / before[ld]) ** 2 for ld in affected])
        return 100.0 * (1.0 - math.sqrt(ratio))

    def affected(self, ev) -> list[str]:
        """Loads whose cross-fitted held-out error drops by at least `min_gain` and by a
        quarter of the largest drop (the loads the effect is about, not those it grazes)."""
        gains = ev.load_gain()
        top = max(gains.values())
        hit = [ld for ld in self.c.loads
               if gains[ld] >= max(self.min_gain, AFFECTED_SHARE * top)]
        return hit or [max(gains, key=gains.get)]

    def _slow(self, res) -> list[dict]:
        """The manoeuvred axis's cycle-averaged part of the residuals `res` (per test flight,
        by channel), by load."""
        return [{ld: r[(ld, "averaged")] for ld in self.c.own} for r in res]

    def redness(self, res) -> float:
        """The colour of the manoeuvred axis's cycle-averaged residual (`_disturbance.py`),
        each load scaled by its baseline mean square."""
        return colour(self._slow(res), self.dts, self.c.own, self.scale)["redness"]

    def fitted(self, model, e: Effect, ev=None):
        """`e` added to `model`, fitted on the training flights (`Engine.choose`). An effect
        the selection admitted (`ev`: the evidence that did) whose fit there acts on no load
        acts on those its cross-fit's fits did (`Engine.on_loads`): its held-out gain came
        from them, and a member that acts on nothing would report no shrink for it."""
        c = self.c
        v = c.engine.choose(c.train_idx, model, e, c.sigma2)
        if v.loads or ev is None:
            return v
        found = {ld for h in ev.variants for ld in h.loads}
        loads = tuple(ld for ld in c.loads if ld in found)
        return c.engine.on_loads(c.train_idx, model, e, c.sigma2, loads) if loads else v

    def models(self, effects, evidence=None):
        """Each effect of `effects` with the model of it and those before it, fitted on the
        training flights in that order, as the selection adds them (`fitted`; `evidence`,
        by name, what admitted each)."""
        model = ()
        for e in effects:
            model = model + ((e, self.fitted(model, e, (evidence or {}).get(e.name))),)
            yield e, model

    def redness_of(self, names) -> float:
        """The redness the explanation of the effects `names` leaves (fitted in that order, as
        the selection would add them)."""
        by = {e.name: e for e in self.c.candidates}
        models = [m for _, m in self.models(by[n] for n in names)]
        return self.redness(self.residuals(models[-1] if models else ()))

    def disturbance(self) -> dict:
        """The baseline's cycle-averaged held-out residual: its colour, size and spectrum."""
        slow = self._slow(self.base)
        out = colour(slow, self.dts, self.c.own, self.scale)
        out.update(spectrum(slow, self.dts, self.c.own), red_min=RED_MIN)
        return out

    def named(self, sel: Selection):
        """The rows of the catalogue effects `sel` chose (`effects`), what its first probe
        says (`unexplained`), and the `(name, member)` of the effects for the simulation."""
        c = self.c
        named = {e.name for e in c.catalogue}
        effects, unexplained, prev, in_sim = [], None, self.rms_before, []
        admitted = {e.name: ev for e, ev in sel.chosen}
        for (e, ev), (_, model) in zip(sel.chosen, self.models((e for e, _ in sel.chosen),
                                                               admitted)):
            res = self.residuals(model)
            now = self.rms_by_load([self.full(r) for r in res])
            affected = self.affected(ev)
            row = {"effect": e.name, "variant": variant_text(model[-1][1], c.axis),
                   "acts_on": list(model[-1][1].loads), "p": ev.p, "affected": affected,
                   "shrink_pct": self.shrink(prev, now, affected),
                   "test_rms_before": prev, "test_rms_after": now,
                   "redness_after": self.redness(res)}
            prev = now
            if e.name in named and unexplained is None:
                first = sel.chosen[0][1]
                row["relative_gain"] = ev.gain / first.gain if first.gain > 0 else 1.0
                effects.append(row)
                in_sim.append((e.name, unwrap(model[-1][1])))
            elif e.name in named:  # after structure outside the catalogue: it may only echo it
                unexplained["then"].append(row)
            elif unexplained is None:
                unexplained = {"probe": e.name, "description": e.description,
                               "drivers": drivers(c.engine, c.train_idx, e, model[-1][1],
                                                  c.sigma2),
                               "test_shrink_pct": row["shrink_pct"], "p": ev.p,
                               "variant": row["variant"], "affected": affected,
                               "redness_after": row["redness_after"], "then": []}
        return effects, unexplained, in_sim

    def row(self, e: Effect, sel: Selection, alpha: float) -> dict:
        """The candidate's row of `diagnosis.json` (fitted alone on the training flights,
        scored on the test flights; its evidence from the last round it was tested in)."""
        c = self.c
        ev, level = sel.last[e.name], sel.level[e.name]
        chosen = e.name in [x.name for x, _ in sel.chosen]
        variant = self.fitted((), e, ev if chosen else None)
        after_band = self.residuals(((e, variant),))
        after_res = [self.full(r) for r in after_band]
        self.augmented[e.name] = after_res
        rms_after = self.rms_by_load(after_res)
        in_band = {ld: (rms(np.concatenate([r[(ld, e.band)] for r in self.base])),
                        rms(np.concatenate([r[(ld, e.band)] for r in after_band])))
                   for ld in c.loads}
        affected = self.affected(ev)
        shrink = self.shrink(self.rms_before, rms_after, affected)
        eb = sum(band_energy(r[ld], s) for r, s in zip(self.before, c.te_sig) for ld in affected)
        ea = sum(band_energy(r[ld], s) for r, s in zip(after_res, c.te_sig) for ld in affected)
        band_drop = {b: 100.0 * (1.0 - a / x) if x > 0 else 0.0
                     for b, x, a in zip(BAND_NAMES, eb, ea)}
        return {
            "effect": e.name,
            "significant": chosen,
            "shrink_pct": shrink,
            "test_rms_before": self.rms_before,
            "test_rms_after": rms_after,
            "affected": affected,
            "band": e.band,
            "variant": variant_text(variant, c.axis),
            "member": member_json(unwrap(variant)),
            "acts_on": list(variant.loads),
            "p": ev.p,
            "confidence": max(0.0, 1.0 - ev.p * alpha / level),
            "detection_limit_pct": 100.0 * ev.detection_limit(level),
            "band_shrink_pct": band_drop,
            "test_rms_in_band": {ld: {"before": b, "after": a} for ld, (b, a) in in_band.items()},
            "evidence": ev.as_dict(level),
            "heldout": heldout_test(self.before, after_res, c.te_sig, affected,
                                    self.rms_before, shrink, level,
                                    [s.name for s in c.te_sig]),
            "description": e.description,
        }

    def ranked(self, effects, sel: Selection, alpha: float) -> list[dict]:
        """The rows of `effects`, the chosen first in their order, then by p value."""
        order = {e.name: k for k, (e, _) in enumerate(sel.chosen)}
        out = [self.row(e, sel, alpha) for e in effects]
        out.sort(key=lambda r: (order.get(r["effect"], len(order)), r["p"]))
        return out
