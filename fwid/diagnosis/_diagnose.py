"""`diagnose`: where the model misses, which unmodelled effect explains it, how far it shrinks."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Sequence

import numpy as np

from .._errors import DiagnosisWarning, FwidError
from ..data import Flight
from ._attribution import unwrap
from ._augment import IN_EOM
from ._campaign import Campaign, campaign
from ._catalogue import CATALOGUE, Effect
from ._confidence import LEVEL, as_rows, confidence_set, explanations, next_flight, sequential
from ._detection import detection_limit
from ._disturbance import RED_MIN, whitens
from ._gapmap import gap_map
from ._probes import PROBES
from ._process_noise import process_noise as fit_process_noise
from ._provenance import provenance
from ._scores import Scores
from ._selection import ALPHA, MIN_GAIN, Selection, forward_select
from ._significance import BLOCK_S
from ._simulation import EarlyFits, SimulationGap, simulation_gap


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
    first probe selected says: drivers and shrink; `None` when no probe is selected),
    `localisation` (the gap map of the baseline on the test flights), `rounds` (the forward
    selection's trace: per round its per-candidate level, every
    candidate's `p`, `t`,
    `gain_pct` and `blocks`, and the effect it `added`, `None` in the round that stopped; why
    a candidate was or was not added), and the held-out load residuals before (`residuals`)
    and after each candidate or probe (`augmented[name]`), by test flight and load, for
    figures; `confidence_set` (the explanations the held-out blocks cannot tell from the
    best, best first), `states` (whether the states came from
    `fwid reconstruct`), `detection` (the smallest gain these flights find with 80 % power
    and how it falls with more flights, `_detection.py`) and `next_input` (the discriminating
    input designed for an ambiguous set, merged into `next_flight`; `None` until designed)."""

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
    detection: dict | None = None
    next_input: dict | None = None

    def candidate(self, name: str) -> dict:
        """The catalogue candidate or probe `name`."""
        for c in self.candidates + self.probes:
            if c["effect"] == name:
                return c
        raise KeyError(name)

    @property
    def next_flight(self) -> dict | None:
        """`_confidence.next_flight` of the set: the flight that tells its rivals apart."""
        nxt = next_flight(self.confidence_set, [c["effect"] for c in self.candidates])
        return None if nxt is None else {**nxt, **(self.next_input or {})}

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
            "detection": self.detection,
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
       An explanation built on the states' dynamics (a probe, or an entry whose columns
       filter the measured states, `Effect.filters_states`: `unsteady-aero`) that leaves the
       held-out residual about as red as before was a proxy of a disturbance, not structure
       (`random-disturbance`; the entries it named are in `disturbance["leaves_red"]`;
       `_disturbance.whitens`): a disturbance drives the states. Otherwise no catalogue
       entry has a rule of its own: each family's size is chosen inside the training
       flights, so all compete on held-out loss alone.

    `verdict` is the first effect of the confidence set's best explanation (least held-out
    loss, each effect charged its smallest gain; `effects` are its catalogue effects, a probe
    first makes it `"unexplained"`; the selection's own model when they agree), then the
    colour rules above: `"unexplained"`, `"random-disturbance"`, or `"none"`. Each
    candidate carries its p value, a `confidence` (one minus the p value corrected over the
    candidates in play) and the detection limit: the held-out error reduction the test
    would have seen with 80 % power.

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
    c = campaign(train, test, axis, cutoff, catalogue, probes, folds, say)
    early = EarlyFits(train, test, axis, cutoff) if simulation else None
    sel = select(c, alpha, min_gain, early, say)
    say("re-fitting on the training flights, scoring on the test flights")
    scores = Scores(c, min_gain)
    disturbance = scores.disturbance()
    say("the confidence set of explanations (model confidence set over the held-out blocks)")
    sel, kept = explain(c, sel)
    effects, unexplained, in_sim = scores.named(sel)
    tracking = {e.name for e in c.candidates if e.filters_states or e.probe}
    k, red = untracked(effects, disturbance["redness"], tracking)
    if red is not None:
        disturbance["leaves_red"] = red
        effects, in_sim, unexplained = effects[:k], in_sim[:k], None
    kept = adequate(kept, scores, disturbance["redness"], tracking,
                    set(disturbance.get("leaves_red", {}).get("effects", ())))
    candidates = scores.ranked(c.catalogue, sel, alpha)
    probe_rows = scores.ranked(c.probes, sel, alpha)
    verdict = verdict_of(effects, unexplained, disturbance)
    if verdict == "unexplained":
        probe = next(e for e, _ in sel.chosen if e.name == unexplained["probe"])
        in_sim = [(probe.name, c.engine.best_variant(c.train_idx, (), probe, c.sigma2))]
    elif verdict not in {e.name for e in c.catalogue}:
        in_sim = []
    noise_block = None
    if process_noise and verdict == "random-disturbance":
        say("fitting the baseline by filter error on the training flights (process noise)")
        noise_block = fit_process_noise(train, axis, cutoff)
    sim, sim_block = None, None
    if simulation:
        say("simulating: baseline and " + (" + ".join(n for n, _ in in_sim) or "nothing added")
            + " fitted by output error on the training flights, simulated on the test flights")
        try:
            sim = simulation_gap(train, test, axis, in_sim, cutoff,
                                 baseline=early.baseline.result(), augmented=early.get(in_sim))
            sim_block = sim.summary
        except (FwidError, np.linalg.LinAlgError) as exc:
            sim_block = failed_block(exc, "simulation")
            sim_block["effects"] = [n for n, _ in in_sim]
        finally:
            early.close()
    say("mapping the gap")
    rounds = [{"level": lv, "added": added,
               "candidates": {k: {"p": ev.p, "t": ev.t, "gain_pct": 100.0 * ev.gain,
                                  "blocks": ev.n} for k, ev in evs.items()}}
              for lv, evs, added in sel.rounds]
    measured = [{ld: s.loads["averaged"][ld] + s.loads["flapping"][ld] for ld in c.loads}
                for s in c.te_sig]
    return Diagnosis(
        axis=axis,
        train=[f.name for f in train],
        test=[f.name for f in test],
        folds=[c.engine.units[i].signals.name for i in c.block_idx],
        verdict=verdict,
        effects=effects,
        candidates=candidates,
        probes=probe_rows,
        unexplained=unexplained,
        disturbance=disturbance,
        simulation=sim_block,
        process_noise=noise_block,
        models=sim,
        first_round={k: {x: r[x] for x in ("p", "gain_pct", "t")}
                     for k, r in (rounds[0]["candidates"] if rounds else {}).items()},
        rounds=rounds,
        localisation=gap_map(c.te_sig, scores.before, measured, axis),
        residuals=scores.before,
        augmented=scores.augmented,
        measured=measured,
        confidence_set=kept,
        states=provenance([f.name for f in c.train + c.test], reconstruction),
        settings=_settings(c, alpha, min_gain),
        detection=_detection(c, sel, min_gain),
    )


def failed_block(exc: BaseException, block: str) -> dict:
    """The record of an optional block (`simulation`, ...) that failed: `{"failed": reason}`,
    the reason one line; the failure is also issued as a `DiagnosisWarning`. The verdict and
    every other block do not depend on it, so the diagnosis goes on."""
    reason = " ".join(f"{type(exc).__name__}: {exc}".split())
    warnings.warn(f"the {block} block failed and is left out ({reason}); the verdict and the "
                  "other blocks stand", DiagnosisWarning, stacklevel=3)
    return {"failed": reason}


def select(c: Campaign, alpha: float, min_gain: float, early: EarlyFits | None,
           say: Callable[[str], None]) -> Selection:
    """Which effects: forward selection over the catalogue and the probes by cross-fit
    (`_selection.py`); the first round's leader starts its augmented fit at once (`early`)."""
    say(f"testing {len(c.catalogue)} candidates and {len(c.probes)} probes by cross-fit over "
        f"{len(c.block_idx)} blocks, forward selection")

    def on_first(e: Effect) -> None:
        if early is not None and e.name in IN_EOM and not e.probe:
            early.start([(e.name, unwrap(c.engine.choose(c.train_idx, (), e, c.sigma2)))])

    return forward_select(c.engine, c.halves, c.candidates, alpha, min_gain,
                          on_first=on_first)


def explain(c: Campaign, sel: Selection) -> tuple[Selection, list[dict]]:
    """The confidence set of explanations (`_confidence.py`) and the selection re-ordered as
    its best explanation (its effects as if selected in that order) when they differ."""
    found = explanations(c.engine, c.halves, sel.first, c.candidates,
                         [e for e, _ in sel.chosen])
    best = confidence_set(found)
    if [e.name for e in best[0].effects] != [e.name for e, _ in sel.chosen]:
        sel = dataclasses.replace(sel, chosen=sequential(c.engine, c.halves, sel.first,
                                                         best[0].effects))
    return sel, as_rows(best, found[0])


def untracked(effects: list[dict], redness: float, tracking: set) -> tuple[int, dict | None]:
    """How many of the named `effects` (rows in the order added, each with the
    `redness_after` it left) stand: up to the first entry built on the states' dynamics
    (`tracking`) that leaves what it entered on about as red as before (`whitens`; from the
    baseline's `redness`): it tracked a disturbance that drove the states, and goes with what
    came after it. Returns the count and, when one went, `{"effects", "redness_after"}`.
    Where the baseline's residual is white (`redness < RED_MIN`) there is no disturbance to
    track and all stand: an effect that takes the residual's higher frequencies (a lag
    does) may leave it redder than it found it."""
    if redness < RED_MIN:
        return len(effects), None
    before = redness
    for k, row in enumerate(effects):
        if row["effect"] in tracking and not whitens(before, row["redness_after"]):
            return k, {"effects": [row["effect"]], "redness_after": row["redness_after"]}
        before = row["redness_after"]
    return len(effects), None


def adequate(kept: list[dict], scores: Scores, before: float, tracking: set,
             tracked: set) -> list[dict]:
    """The confidence set without the explanations that track a disturbance: those holding
    an entry the verdict found tracking it (`tracked`), and those holding an entry built on
    the states' dynamics or a probe (`tracking`) that do not whiten the residual (`whitens`,
    the verdict's test; each such row carries its `redness_after`); `before`: the baseline
    residual's redness (white: no disturbance to track, all stay, as in `untracked`)."""
    if before < RED_MIN:
        return list(kept)
    out = []
    for row in kept:
        if tracked & set(row["explanation"]):
            continue
        if tracking & set(row["explanation"]):
            row["redness_after"] = scores.redness_of(row["explanation"])
            if not whitens(before, row["redness_after"]):
                continue
        out.append(row)
    return out


def verdict_of(effects: list[dict], unexplained: dict | None, disturbance: dict) -> str:
    """The first catalogue effect named; else `"unexplained"` when a probe predicts the gap
    and whitens the residual (`whitens`); else the residual's colour: `"random-disturbance"`
    when red, or when an explanation was found that does not whiten it
    (`disturbance["leaves_red"]`, catalogue entries; for a probe, `unexplained`): a
    disturbance drives the states, so functions of them predict part of it (its proxy), but
    what is left stays as red, where a deterministic effect, once fitted, leaves the noise.
    The same adequacy test (`whitens`) for every explanation built on the states' dynamics,
    probe or catalogue entry (`untracked`); `"none"` when white."""
    if effects:
        return effects[0]["effect"]
    if unexplained is not None and whitens(disturbance["redness"],
                                           unexplained["redness_after"]):
        return "unexplained"
    red = (disturbance["redness"] >= RED_MIN or unexplained is not None
           or "leaves_red" in disturbance)
    return "random-disturbance" if red else "none"


def _detection(c: Campaign, sel: Selection, min_gain: float) -> dict | None:
    """`diagnosis.json`'s `detection`: the first round's limit and its flight-count rule."""
    if not sel.rounds:
        return None
    lim = detection_limit(sel.first, [e.name for e in c.catalogue], sel.rounds[0][0],
                          min_gain, len(c.train), len(c.test))
    return None if lim is None else lim.as_dict()


def _settings(c: Campaign, alpha: float, min_gain: float) -> dict:
    """`diagnosis.json`'s `method`: how the diagnosis was made."""
    return {
        "baseline": "Eqs. 2-6 below the split + Eq. 12 (3 harmonics) above it, "
                    "per-flight trim and Fourier coefficients, equation error",
        "split_hz": c.cutoff,
        "significance": ("cross-fit (fit on training, score test blocks; fit on test, "
                         "score training blocks)" if len(c.halves) == 2 else
                         f"cross-fit over {len(c.halves)} folds of flights (each fold's "
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
        "blocks": len(c.block_idx),
        "loads": list(c.loads),
    }
