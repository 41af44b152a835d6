"""`diagnose`: where the model misses, which unmodelled effect explains it, how far it shrinks."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

import numpy as np

from .._errors import ExcitationError
from ..data import Flight
from ._attribution import (
    ALPHA,
    MIN_FOLDS,
    MIN_GAIN,
    Engine,
    cross_validate,
    load_tests,
    significant_loads,
    units,
)
from ._catalogue import CATALOGUE, Effect
from ._gapmap import BAND_NAMES, band_energy, gap_map, rms
from ._signals import AXIS_INPUT, AXIS_LOADS, BANDS, LOADS, check_axis, signals


@dataclasses.dataclass
class Diagnosis:
    """The result of [`fwid.diagnose`][]: `verdict` (an effect name or `"none"`),
    `candidates` (ranked, best first, CONTRACTS section 3), `localisation` (the gap map of the
    baseline on the test flights), and the held-out load residuals before (`residuals`) and
    after each candidate (`augmented[name]`), by test flight and load, for figures."""

    axis: str
    train: list[str]
    test: list[str]
    folds: list[str]
    verdict: str
    candidates: list[dict]
    localisation: dict
    residuals: list[dict] = dataclasses.field(repr=False)
    augmented: dict = dataclasses.field(repr=False)
    measured: list[dict] = dataclasses.field(repr=False)
    settings: dict = dataclasses.field(default_factory=dict)

    def candidate(self, name: str) -> dict:
        for c in self.candidates:
            if c["effect"] == name:
                return c
        raise KeyError(name)

    def to_json(self) -> dict:
        """`diagnosis.json` (CONTRACTS section 3)."""
        return {
            "verdict": self.verdict,
            "axis": self.axis,
            "train": self.train,
            "test": self.test,
            "candidates": self.candidates,
            "localisation": self.localisation,
            "method": self.settings,
        }


def _variant_text(v) -> str | None:
    if v is None:
        return None
    kind, tau = v
    return f"first-order lag, tau = {tau:g} s" if kind == "lag" else f"delay {tau:g} s"


def _check_excitation(sigs, axis: str) -> None:
    d = AXIS_INPUT[axis]
    moves = [np.ptp(s.slow[d]) for s in sigs]
    if max(moves) < 1e-3:  # rad: a twentieth of a degree
        raise ExcitationError(
            f"too little excitation to diagnose the {axis} axis: '{d}' moves by at most "
            f"{max(moves):.2g} rad in the training flights ({', '.join(s.name for s in sigs)}); "
            "use flights with a manoeuvre (a 3211 or doublet on the control)"
        )


def diagnose(
    train: Sequence[Flight],
    test: Sequence[Flight],
    *,
    axis: str = "lon",
    catalogue: Sequence[Effect] = CATALOGUE,
    cutoff: float = 5.0,
    alpha: float = ALPHA,
    min_gain: float = MIN_GAIN,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Diagnose the sim-to-real gap of the paper's model on held-out flights.

    The baseline is the paper's model of the loads: the cycle-averaged linear model of
    Eqs. (2-6) below the split and the 3-harmonic Fourier series of Eq. (12) above it, with a
    flight's trim load and Fourier coefficients its own (re-estimated on every flight, as bias
    terms are). It is fitted by least squares to the loads reconstructed from the motion
    (equation error): fast, and exact for the linear-in-parameters augmentations of the
    catalogue.

    1. **Which**: each effect of `catalogue` adds its regressors; its out-of-sample value is
       measured by leave-one-flight-out cross-validation on the training flights, and a
       one-sided t test across folds with a Bonferroni correction over every (candidate,
       load) pair decides significance (`fwid.diagnose._attribution`).
    2. **How far**: baseline and candidates are re-fitted on all training flights and scored on
       the test flights only: RMS per load before and after, and `shrink_pct`, the drop of the
       RMS of the affected loads (each relative to its baseline RMS). A candidate counts as
       significant only if the held-out error goes down too.
    3. **Where**: the gap map of the baseline on the test flights (`gap_map`).

    `verdict` is the best significant candidate, or `"none"`.

    **Arguments:** `train`, `test` (flights), `axis` (`"lon"`/`"lat"`, the manoeuvre's axis),
    `catalogue`, `cutoff` (the split [Hz]), `alpha` (family-wise false-alarm level),
    `min_gain` (smallest held-out relative drop of a load's mean-square error that counts),
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
    _check_excitation(tr_sig, axis)
    blocks = max(1, math.ceil(MIN_FOLDS / len(tr_sig)))
    folds = [s.block(b, blocks) for s in tr_sig for b in range(blocks)] if blocks > 1 else tr_sig
    fold_units = units(folds)
    n_folds = len(fold_units)
    engine = Engine(fold_units + units(te_sig), loads, catalogue)
    fold_idx = list(range(n_folds))
    test_idx = list(range(n_folds, n_folds + len(te_sig)))

    say(f"cross-validating {len(catalogue)} candidates over {n_folds} folds")
    cv = cross_validate(engine, fold_idx)
    n_tests = sum(len(engine.channels(e.band)) for e in catalogue)

    say("re-fitting on all training flights, scoring on the test flights")
    sigma2, base_res = {}, [{} for _ in test_idx]
    for band in BANDS:
        for ch in engine.channels(band):
            th, sse = engine.fit(fold_idx, ch)
            sigma2[ch] = max(sse, 1e-300)
            for j, i in enumerate(test_idx):
                base_res[j][ch] = engine.residual(i, ch, th)

    def full(res):
        return {ld: res[(ld, "averaged")] + res[(ld, "flapping")] for ld in loads}

    before = [full(r) for r in base_res]
    rms_before = {ld: rms(np.concatenate([r[ld] for r in before])) for ld in loads}

    candidates, augmented = [], {}
    for e in catalogue:
        tests = load_tests(cv, e.name)
        sig_ch = significant_loads(tests, n_tests, alpha, min_gain)
        variant, thetas = engine.fit_effect(fold_idx, e, sigma2)
        after_res, after_band = [], []
        for j, i in enumerate(test_idx):
            res = dict(base_res[j])
            for ch, th in thetas.items():
                res[ch] = engine.residual(i, ch, th, e, variant)
            after_band.append(res)
            after_res.append(full(res))
        augmented[e.name] = after_res
        rms_after = {ld: rms(np.concatenate([r[ld] for r in after_res])) for ld in loads}
        in_band = {ch[0]: (rms(np.concatenate([r[ch] for r in base_res])),
                           rms(np.concatenate([r[ch] for r in after_band])))
                   for ch in thetas}
        best_ch = max(tests, key=lambda ch: tests[ch].t)
        affected = [ch[0] for ch in sig_ch] or [best_ch[0]]
        ratio = np.mean([(rms_after[ld] / rms_before[ld]) ** 2 for ld in affected])
        shrink = 100.0 * (1.0 - math.sqrt(ratio))
        eb = sum(band_energy(r[ld], s) for r, s in zip(before, te_sig) for ld in affected)
        ea = sum(band_energy(r[ld], s) for r, s in zip(after_res, te_sig) for ld in affected)
        band_drop = {b: 100.0 * (1.0 - a / e) if e > 0 else 0.0
                     for b, e, a in zip(BAND_NAMES, eb, ea)}
        significant = bool(sig_ch) and shrink > 0.0
        score = sum(tests[ch].gain for ch in sig_ch)
        candidates.append({
            "effect": e.name,
            "significant": significant,
            "shrink_pct": shrink,
            "test_rms_before": {ld: rms_before[ld] for ld in loads},
            "test_rms_after": rms_after,
            "affected": affected,
            "band": e.band,
            "variant": _variant_text(variant),
            "band_shrink_pct": band_drop,
            "test_rms_in_band": {ld: {"before": b, "after": a} for ld, (b, a) in in_band.items()},
            "evidence": {ch[0]: tests[ch].as_dict for ch in tests},
            "description": e.description,
            "_rank": (significant, score if significant else tests[best_ch].t),
        })
    candidates.sort(key=lambda c: c.pop("_rank"), reverse=True)
    verdict = candidates[0]["effect"] if candidates and candidates[0]["significant"] else "none"

    say("mapping the gap")
    measured = [{ld: s.loads["averaged"][ld] + s.loads["flapping"][ld] for ld in loads}
                for s in te_sig]
    localisation = gap_map(te_sig, before, measured, axis)
    return Diagnosis(
        axis=axis,
        train=[f.name for f in train],
        test=[f.name for f in test],
        folds=cv.folds,
        verdict=verdict,
        candidates=candidates,
        localisation=localisation,
        residuals=before,
        augmented=augmented,
        measured=measured,
        settings={
            "baseline": "Eqs. 2-6 below the split + Eq. 12 (3 harmonics) above it, "
                        "per-flight trim and Fourier coefficients, equation error",
            "split_hz": cutoff,
            "significance": "leave-one-fold-out cross-validation, one-sided t test on per-fold "
                            "log MSE ratios, Bonferroni over candidate x load pairs",
            "alpha": alpha,
            "min_gain_pct": 100 * min_gain,
            "tests": n_tests,
            "folds": n_folds,
            "loads": list(loads),
        },
    )
