"""`diagnose`: where the model misses, which unmodelled effect explains it, how far it shrinks."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

import numpy as np

from ..data import Flight
from ._attribution import Engine, units, unwrap
from ._catalogue import CATALOGUE, Effect, filter_text, quadratic_names
from ._confidence import LEVEL, as_rows, confidence_set, explanations, next_flight, sequential
from ._disturbance import RED_MIN, colour, rates_proxy, spectrum
from ._gapmap import BAND_NAMES, band_energy, gap_map, rms
from ._probes import PROBES, drivers
from ._provenance import provenance
from ._process_noise import process_noise as fit_process_noise
from ._augment import IN_EOM
from ._simulation import EarlyFits, SimulationGap, simulation_gap, start_baseline
from ._selection import ALPHA, MIN_GAIN, forward_select
from ._significance import BLOCK_S, cross_fit_folds, scoring_blocks
from ._signals import AXIS_LOADS, BANDS, LOADS, check_axis, check_excitation, signals


@dataclasses.dataclass
class Diagnosis:
    """The result of [`fwid.diagnose`][]: `verdict` (an effect name, `"unexplained"`,
    `"random-disturbance"` or `"none"`), `disturbance` (the colour, size and spectrum of the
    baseline's cycle-averaged held-out residual), `process_noise` (with a
    `"random-disturbance"` verdict, the baseline fitted by filter error on the training
    flights: the process noise F it takes and whether its innovations are white; `None`
    otherwise), `candidates` (the catalogue, ranked, best first; the keys of `diagnosis.json`
    on the guide's 'Formats and interfaces' page), `probes`
    (the same for the structure outside the catalogue), `unexplained` (what the
    first probe selected says: drivers and shrink; `None` when no probe is selected, or when
    it came first after a proxy of a disturbance was set aside),
    `localisation` (the gap map of the baseline on the test flights), `rounds` (the forward
    selection's trace (after a proxy of a disturbance was set aside, the second selection's;
    the proxy is in `disturbance["proxy"]`): per round its per-candidate level, every
    candidate's `p`, `t`,
    `gain_pct` and `blocks`, and the effect it `added`, `None` in the round that stopped; why
    a candidate was or was not added), and the held-out load residuals before (`residuals`)
    and after each candidate or probe (`augmented[name]`), by test flight and load, for
    figures; `confidence_set` (the explanations the held-out blocks cannot tell from the
    best, best first) and `states` (whether the states came from
    `fwid reconstruct`)."""

    axis: str
    train: list[str]
    test: list[str]
    folds: list[str]
    verdict: str
    effects: list[dict]
    candidates: list[dict]
    localisation: dict
    residuals: list[dict] = dataclasses.field(repr=False)
    augmented: dict = dataclasses.field(repr=False)
    measured: list[dict] = dataclasses.field(repr=False)
    probes: list[dict] = dataclasses.field(default_factory=list, repr=False)
    unexplained: dict | None = None
    disturbance: dict | None = None
    first_round: dict = dataclasses.field(default_factory=dict, repr=False)
    rounds: list[dict] = dataclasses.field(default_factory=list, repr=False)
    simulation: dict | None = None
    process_noise: dict | None = None
    models: SimulationGap | None = dataclasses.field(default=None, repr=False)
    confidence_set: list[dict] = dataclasses.field(default_factory=list)
    states: dict | None = None
    settings: dict = dataclasses.field(default_factory=dict)

    def candidate(self, name: str) -> dict:
        """The catalogue candidate or probe `name`."""
        for c in self.candidates + self.probes:
            if c["effect"] == name:
                return c
        raise KeyError(name)

    @property
    def next_flight(self) -> dict | None:
        """`_confidence.next_flight` of the set: the flight that tells its rivals apart."""
        return next_flight(self.confidence_set, [c["effect"] for c in self.candidates])

    @property
    def lead(self) -> dict | None:
        """The candidate behind the verdict: the effect named, the probe of an
        `"unexplained"` verdict, or `None`."""
        if self.verdict == "unexplained":
            return self.candidate(self.unexplained["probe"])
        named = {c["effect"] for c in self.candidates}
        return self.candidate(self.verdict) if self.verdict in named else None

    def to_json(self) -> dict:
        """`diagnosis.json` (the report format)."""
        return {
            "verdict": self.verdict,
            "effects": self.effects,
            "axis": self.axis,
            "train": self.train,
            "test": self.test,
            "candidates": self.candidates,
            "confidence_set": self.confidence_set,
            "next_flight": self.next_flight,
            "unexplained": self.unexplained,
            "probes": self.probes,
            "disturbance": self.disturbance,
            "process_noise": self.process_noise,
            "states": self.states,
            "simulation": self.simulation,
            "localisation": self.localisation,
            "first_round": self.first_round,
            "rounds": self.rounds,
            "method": self.settings,
        }


def _variant_text(v, axis: str = "lon") -> str | None:
    v = unwrap(v)
    if v is None:
        return None
    if isinstance(v, float):  # a time constant or lead (0: at once)
        return f"{v:g} s" if v else "at once"
    if all(isinstance(k, int) for k in v):  # a subset of nonlinear-aero's terms
        names = quadratic_names(axis)
        return "terms " + ", ".join(names[k] for k in v)
    return filter_text(v)


#: A load is affected by an effect when its held-out gain is at least this share of the
#: largest gain over the loads.
AFFECTED_SHARE = 0.25


def diagnose(
    train: Sequence[Flight],
    test: Sequence[Flight],
    *,
    axis: str = "lon",
    catalogue: Sequence[Effect] = CATALOGUE,
    probes: Sequence[Effect] = PROBES,
    cutoff: float = 5.0,
    alpha: float = ALPHA,
    min_gain: float = MIN_GAIN,
    folds: int | None = None,
    simulation: bool = True,
    process_noise: bool = True,
    reconstruction: Sequence[dict | None] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Diagnose the sim-to-real gap of the paper's model on held-out flights.

    The baseline is the paper's model of the loads: the cycle-averaged linear model of
    Eqs. (2-6) below the split and the 3-harmonic Fourier series of Eq. (12) above it, with a
    flight's trim load and Fourier coefficients its own (re-estimated on every flight, as bias
    terms are). It is fitted by least squares to the loads reconstructed from the motion
    (equation error): fast, and exact for the linear-in-parameters augmentations of the
    catalogue.

    1. **Which**: each effect of `catalogue` adds its regressors, on the loads where they
       lower the fitting flights' leave-one-flight-out error (`acts_on` in each row; an
       effect that replaces the deflection acts on all). Its out-of-sample value is
       measured by a cross-fit (fitted on the training flights and scored on the test
       flights' blocks of about 1 s, and the other way round), pooled over the loads of its
       band, and judged by a one-sided t test across blocks. Effects are
       added by forward selection while one passes at `alpha` divided by the candidates still
       in play: `effects` lists them in the order added, each with its
       held-out gain relative to the first's (`relative_gain`).
       How sure the choice is, the **confidence set** says: every
       explanation (none, each candidate or probe, the pairs of the best four, the
       selection's model; `unsteady-aero` alone only) that the held-out blocks cannot
       reject against the best at `_confidence.LEVEL` (Hansen, Lunde & Nason's model
       confidence set), best first, each with its held-out gain and p value
       (`confidence_set`). Two or more kept: the data cannot tell them apart; a pair
       kept: both effects may be there.
    2. **How far**: baseline and candidates are re-fitted on the training flights only and
       scored on the test flights: RMS per load before and after, and `shrink_pct`, the drop
       of the RMS of the affected loads (each relative to its baseline RMS).
    3. **Where**: the gap map of the baseline on the test flights (`gap_map`).

    The probes (the attitude, a drift over the flight) take
    part in the selection as rivals: when one enters first, the gap is
    predictable from what was measured but no catalogue entry explains it, and the verdict is
    `"unexplained"` (with the probe's `drivers`), never the catalogue entry that merely
    correlates with it.

    4. **Nothing named**: the colour of the held-out residual tells a
       disturbance nothing measured predicts (`"random-disturbance"`: red, as gusts make it)
       from measurement noise (`"none"`: the model is adequate, up to the detection limit).
       A probe that leaves the residual red was a proxy of a disturbance, not structure; so
       was a catalogue entry built on states' rates (`unsteady-aero`), selected first, that
       leaves it red (`disturbance["proxy"]` says which): it is set aside with all that
       entered after it, and the selection runs again without such entries, which may name
       the catalogue effects the disturbance hid (`random-disturbance` when it names none
       first: a probe would track the disturbance too).

    `verdict` is the first effect of the confidence set's best explanation (least held-out
    loss, each effect charged its smallest gain; `effects` are its catalogue effects, a probe
    first makes it `"unexplained"`; the selection's own model when they agree), then the
    colour rules above: `"unexplained"`, `"random-disturbance"`, or `"none"`. Each candidate carries its p value,
    a `confidence` (one minus the p value corrected over the candidates in play) and the
    detection limit: the held-out error reduction the test would have seen with 80 % power.

    **Arguments:** `train`, `test` (flights), `axis` (`"lon"`/`"lat"`, the manoeuvre's axis),
    `catalogue`, `probes` (rivals outside the catalogue; `()` for none), `cutoff` (the split
    [Hz]), `alpha` (family-wise false-alarm level per selection round), `min_gain` (smallest
    typical held-out relative error drop that counts), `folds` (of the cross-fit: 2,
    training vs test, or more, each group of flights scored by the model fitted on all the
    others; `None`: eight for a campaign of at most eight flights, else two,
    `_significance.default_folds`),
    `simulation` (also measure the gap in the simulated states, the
    verdict's effects put into the EOM, re-estimated by output error on the training flights,
    simulated on the test flights; `Diagnosis.models` keeps both identifications),
    `process_noise` (with a `"random-disturbance"` verdict, also fit the baseline by filter
    error on the training flights, Jategaonkar Ch. 5, the process noise
    as evidence; a failed fit is recorded in the block, never raised), `reconstruction`
    (per training then test flight, its entry in the `reconstruction.json` beside it, as
    `read_reconstruction` returns them: reported beside the verdict as the `states` block),
    `progress` (called with a line of text at each stage).
    """
    say = progress or (lambda msg: None)
    check_axis(train, axis, "training")
    check_axis(test, axis, "test")
    flights = list(train) + list(test)
    loads = tuple(ld for ld in LOADS if all(ld in f for f in flights))
    loads = tuple(ld for ld in loads if ld in AXIS_LOADS[axis]) + tuple(
        ld for ld in loads if ld not in AXIS_LOADS[axis])
    say(f"decomposing {len(train)} training and {len(test)} test flights")
    tr_sig = [signals(f, cutoff=cutoff) for f in train]
    te_sig = [signals(f, cutoff=cutoff) for f in test]
    check_excitation(tr_sig, axis)
    baseline = start_baseline(train, test, axis, cutoff) if simulation else None
    tr_blocks, tr_par = scoring_blocks(tr_sig, 0)
    te_blocks, te_par = scoring_blocks(te_sig, len(tr_sig))
    engine = Engine(units(tr_sig + te_sig) + units(tr_blocks + te_blocks, tr_par + te_par),
                    loads, tuple(catalogue) + tuple(probes), own=AXIS_LOADS[axis])
    n_tr, n_te, n_trb = len(tr_sig), len(te_sig), len(tr_blocks)
    train_idx = tuple(range(n_tr))
    test_idx = tuple(range(n_tr, n_tr + n_te))
    trb_idx = tuple(range(n_tr + n_te, n_tr + n_te + n_trb))
    teb_idx = tuple(range(n_tr + n_te + n_trb, len(engine.units)))
    sigma2 = engine.mean_square(train_idx)
    halves = cross_fit_folds(engine, n_tr + n_te, [p for p, _ in tr_par + te_par], n_tr,
                             folds)

    say(f"testing {len(catalogue)} candidates and {len(probes)} probes by cross-fit over "
        f"{len(trb_idx) + len(teb_idx)} blocks, forward selection")
    early = EarlyFits(train, test, axis, cutoff) if simulation else None

    def on_first(e: Effect) -> None:  # the leader's augmented fit starts now (`EarlyFits`)
        if early is not None and e.name in IN_EOM and not e.probe:
            early.start([(e.name, unwrap(engine.choose(train_idx, (), e, sigma2)))])

    sel = forward_select(engine, halves, tuple(catalogue) + tuple(probes), alpha, min_gain,
                         on_first=on_first)

    say("re-fitting on the training flights, scoring on the test flights")

    def test_residuals(model):
        out = [{} for _ in test_idx]
        for band in BANDS:
            for ch in engine.channels(band):
                th, _ = engine.fit(train_idx, ch, model)
                for j, i in enumerate(test_idx):
                    out[j][ch] = engine.residual(i, ch, th, model)
        return out

    def full(res):
        return {ld: res[(ld, "averaged")] + res[(ld, "flapping")] for ld in loads}

    def rms_by_load(res_full):
        return {ld: rms(np.concatenate([r[ld] for r in res_full])) for ld in loads}

    def shrink(before, after, affected):
        ratio = np.mean([(after[ld] / before[ld]) ** 2 for ld in affected])
        return 100.0 * (1.0 - math.sqrt(ratio))

    def affected_loads(ev):
        """Loads whose cross-fitted held-out error drops by at least `min_gain` and by a
        quarter of the largest drop (the loads the effect is about, not those it grazes)."""
        gains = ev.load_gain()
        top = max(gains.values())
        hit = [ld for ld in loads if gains[ld] >= max(min_gain, AFFECTED_SHARE * top)]
        return hit or [max(gains, key=gains.get)]

    base_res = test_residuals(())
    before = [full(r) for r in base_res]
    rms_before = rms_by_load(before)
    own = [ld for ld in loads if ld in AXIS_LOADS[axis]]
    dts = [s.dt for s in te_sig]
    own_scale = {ld: sigma2[(ld, "averaged")] for ld in own}

    def slow_part(res):
        return [{ld: r[(ld, "averaged")] for ld in own} for r in res]

    named = {e.name for e in catalogue}

    def name_effects(sel):
        """The rows of the catalogue effects `sel` chose (`effects`), what its first probe says
        (`unexplained`), and the `(name, variant)` of the effects for the simulation."""
        effects, unexplained, model, prev, in_sim = [], None, (), rms_before, []
        for e, ev in sel.chosen:
            model = model + ((e, engine.choose(train_idx, model, e, sigma2)),)
            res = test_residuals(model)
            now = rms_by_load([full(r) for r in res])
            affected = affected_loads(ev)
            row = {"effect": e.name, "variant": _variant_text(model[-1][1], axis),
                   "acts_on": list(model[-1][1].loads), "p": ev.p, "affected": affected,
                   "shrink_pct": shrink(prev, now, affected),
                   "test_rms_before": prev, "test_rms_after": now}
            prev = now
            if e.rates and not effects and unexplained is None:
                row["redness_after"] = colour(slow_part(res), dts, own, own_scale)["redness"]
                row["shortest_lag"] = unwrap(model[-1][1]) == min(e.variants)
            if e.name in named and unexplained is None:
                first = sel.chosen[0][1]
                row["relative_gain"] = ev.gain / first.gain if first.gain > 0 else 1.0
                effects.append(row)
                in_sim.append((e.name, unwrap(model[-1][1])))
            elif e.name in named:  # after structure outside the catalogue: it may only echo it
                unexplained["then"].append(row)
            elif unexplained is None:
                unexplained = {"probe": e.name, "description": e.description,
                               "drivers": drivers(engine, train_idx, e, model[-1][1], sigma2),
                               "test_shrink_pct": row["shrink_pct"], "p": ev.p,
                               "variant": row["variant"], "affected": affected,
                               "redness_after": colour(slow_part(res), dts, own,
                                                       own_scale)["redness"], "then": []}
        return effects, unexplained, in_sim

    disturbance = colour(slow_part(base_res), dts, own, own_scale)
    disturbance.update(spectrum(slow_part(base_res), dts, own), red_min=RED_MIN)
    effects, unexplained, in_sim = name_effects(sel)
    set_aside = sel
    if effects and rates_proxy(effects[0], disturbance):
        # an entry built on states' rates that leaves the residual red, or that takes its
        # shortest lag (a rate) on a red residual, tracked a disturbance: set aside, with all
        # that entered after it (it may track the proxy's leftovers); the selection is run
        # again without such entries, which may find the effects the disturbance hid
        proxy = effects[0]
        disturbance["proxy"] = {k: proxy[k] for k in ("effect", "variant", "p", "shrink_pct",
                                                       "redness_after", "shortest_lag")}
        say(f"{proxy['effect']} tracked a disturbance: selecting again without it")
        sel = forward_select(engine, halves, [e for e in tuple(catalogue) + tuple(probes)
                                              if not e.rates], alpha, min_gain)
        effects, unexplained, in_sim = name_effects(sel)
        if not effects:  # a probe first on the same residual tracks the disturbance too
            unexplained = None
    say("the confidence set of explanations (model confidence set over the held-out blocks)")
    # an entry built on rates set aside as a proxy of a disturbance explains nothing here
    pool = tuple(e for e in tuple(catalogue) + tuple(probes)
                 if not (e.rates and "proxy" in disturbance))
    found = explanations(engine, halves, set_aside.first, pool, [e for e, _ in sel.chosen])
    best = confidence_set(found)
    if [e.name for e in best[0].effects] != [e.name for e, _ in sel.chosen]:
        # the verdict is the best explanation's: its effects as if selected in that order
        sel = dataclasses.replace(sel, chosen=sequential(engine, halves, set_aside.first,
                                                         best[0].effects))
        effects, unexplained, in_sim = name_effects(sel)
        if effects and effects[0].get("redness_after") is not None and rates_proxy(
                effects[0], disturbance):  # as above: a proxy of a disturbance
            disturbance["proxy"] = {k: effects[0][k] for k in (
                "effect", "variant", "p", "shrink_pct", "redness_after", "shortest_lag")}
            found = [x for x in found if not any(e.rates for e in x.effects)]
            best = confidence_set(found)
            sel = dataclasses.replace(sel, chosen=sequential(engine, halves, set_aside.first,
                                                             best[0].effects))
            effects, unexplained, in_sim = name_effects(sel)
        if "proxy" in disturbance and not effects:  # a probe tracks the disturbance too
            unexplained = None
    kept = as_rows(best, found[0])
    chosen = [e.name for e, _ in sel.chosen]
    last, levels = {**set_aside.last, **sel.last}, {**set_aside.level, **sel.level}
    augmented: dict = {}

    def describe(e: Effect) -> dict:
        ev = last[e.name]
        variant = engine.choose(train_idx, (), e, sigma2)
        after_band = test_residuals(((e, variant),))
        after_res = [full(r) for r in after_band]
        augmented[e.name] = after_res
        rms_after = rms_by_load(after_res)
        in_band = {ld: (rms(np.concatenate([r[(ld, e.band)] for r in base_res])),
                        rms(np.concatenate([r[(ld, e.band)] for r in after_band])))
                   for ld in loads}
        affected = affected_loads(ev)
        eb = sum(band_energy(r[ld], s) for r, s in zip(before, te_sig) for ld in affected)
        ea = sum(band_energy(r[ld], s) for r, s in zip(after_res, te_sig) for ld in affected)
        band_drop = {b: 100.0 * (1.0 - a / x) if x > 0 else 0.0
                     for b, x, a in zip(BAND_NAMES, eb, ea)}
        level = levels[e.name]
        return {
            "effect": e.name,
            "significant": e.name in chosen,
            "shrink_pct": shrink(rms_before, rms_after, affected),
            "test_rms_before": rms_before,
            "test_rms_after": rms_after,
            "affected": affected,
            "band": e.band,
            "variant": _variant_text(variant, axis),
            "acts_on": list(variant.loads),
            "p": ev.p,
            "confidence": max(0.0, 1.0 - ev.p * alpha / level),
            "detection_limit_pct": 100.0 * ev.detection_limit(level),
            "band_shrink_pct": band_drop,
            "test_rms_in_band": {ld: {"before": b, "after": a} for ld, (b, a) in in_band.items()},
            "evidence": ev.as_dict(level),
            "description": e.description,
        }

    order = {name: k for k, name in enumerate(chosen)}

    def ranked(effects):
        out = [describe(e) for e in effects]
        out.sort(key=lambda c: (order.get(c["effect"], len(order)), c["p"]))
        return out

    candidates, probe_rows = ranked(catalogue), ranked(probes)
    verdict = effects[0]["effect"] if effects else "unexplained" if unexplained else "none"
    # a probe that leaves the residual as red as a disturbance found a proxy of it (a state
    # that integrates the disturbance), not structure; nothing at all found and a red
    # residual: a disturbance nothing measured predicts
    if verdict == "unexplained" and unexplained["redness_after"] >= RED_MIN:
        verdict = "random-disturbance"
    elif verdict == "none" and (disturbance["redness"] >= RED_MIN or "proxy" in disturbance):
        verdict = "random-disturbance"
    if verdict == "unexplained":
        probe = next(e for e, _ in sel.chosen if e.name == unexplained["probe"])
        in_sim = [(probe.name, engine.best_variant(train_idx, (), probe, sigma2))]
    elif verdict not in named:
        in_sim = []
    noise_block = None
    if process_noise and verdict == "random-disturbance":
        say("fitting the baseline by filter error on the training flights (process noise)")
        noise_block = fit_process_noise(train, axis, cutoff)
    sim = None
    if simulation:
        say("simulating: baseline and " + (" + ".join(n for n, _ in in_sim) or "nothing added")
            + " fitted by output error on the training flights, simulated on the test flights")
        sim = simulation_gap(train, test, axis, in_sim, cutoff, baseline=baseline.result(),
                             augmented=early.get(in_sim))

    say("mapping the gap")
    rounds = [{"level": lv, "added": added,
               "candidates": {k: {"p": ev.p, "t": ev.t, "gain_pct": 100.0 * ev.gain,
                                  "blocks": ev.n} for k, ev in evs.items()}}
              for lv, evs, added in sel.rounds]
    measured = [{ld: s.loads["averaged"][ld] + s.loads["flapping"][ld] for ld in loads}
                for s in te_sig]
    localisation = gap_map(te_sig, before, measured, axis)
    return Diagnosis(
        axis=axis,
        train=[f.name for f in train],
        test=[f.name for f in test],
        folds=[engine.units[i].signals.name for i in trb_idx + teb_idx],
        verdict=verdict,
        effects=effects,
        candidates=candidates,
        probes=probe_rows,
        unexplained=unexplained,
        disturbance=disturbance,
        simulation=sim.summary if sim is not None else None,
        process_noise=noise_block,
        models=sim,
        first_round={k: {x: c[x] for x in ("p", "gain_pct", "t")}
                     for k, c in (rounds[0]["candidates"] if rounds else {}).items()},
        rounds=rounds,
        localisation=localisation,
        residuals=before,
        augmented=augmented,
        measured=measured,
        confidence_set=kept,
        states=provenance([f.name for f in flights], reconstruction),
        settings={
            "baseline": "Eqs. 2-6 below the split + Eq. 12 (3 harmonics) above it, "
                        "per-flight trim and Fourier coefficients, equation error",
            "split_hz": cutoff,
            "significance": ("cross-fit (fit on training, score test blocks; fit on test, "
                             "score training blocks)" if len(halves) == 2 else
                             f"cross-fit over {len(halves)} folds of flights (each fold's "
                             "blocks scored by the model fitted on the other flights)")
                            + ", loads pooled per candidate, one-sided t test on "
                            "per-block log error ratios, forward selection at alpha / "
                            "candidates in play",
            "alpha": alpha,
            "min_gain_pct": 100 * min_gain,
            "block_s": BLOCK_S,
            "confidence_level": LEVEL,
            "confidence_set": f"model confidence set (Hansen, Lunde & Nason 2011, T_max, "
                              f"block bootstrap over the scoring blocks) at level {LEVEL:g} "
                              f"over none, each candidate and probe, pairs and the selection",
            "blocks": len(trb_idx) + len(teb_idx),
            "loads": list(loads),
        },
    )
