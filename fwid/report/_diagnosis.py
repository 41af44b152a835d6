"""The diagnosis in words (terminal) and in one figure (the gap map and the shrink)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..diagnosis import BAND_NAMES, Diagnosis
from ..diagnosis._provenance import provenance_text
from ..diagnosis._simulation import fixed_text
from ..diagnosis._signals import AXIS_LOADS

_BAND_LABELS = ("<5 Hz", "1f", "2f", "3f", "1f±", "2f±", "3f±", "rest")


def _band_label(band: str) -> str:
    """A band of the gap map as the figure labels it ("<5 Hz", "2f", "2f±", ...)."""
    return dict(zip(BAND_NAMES, _BAND_LABELS)).get(band, band)


def in_band_shrink(c: dict) -> float | None:
    """The drop (%) of the held-out RMS within the effect's own band, over its affected loads
    (`test_rms_in_band`): the headline shrink, where the effect acts."""
    band = c.get("test_rms_in_band", {})
    pairs = [(band[ld]["before"], band[ld]["after"]) for ld in c["affected"] if ld in band]
    pairs = [(b, a) for b, a in pairs if b > 0]
    if not pairs:
        return None
    return 100.0 * (1.0 - float(np.sqrt(np.mean([(a / b) ** 2 for b, a in pairs]))))


def _shrink_text(c: dict) -> str:
    band = in_band_shrink(c)
    overall = f"{c['shrink_pct']:.1f} % over all frequencies"
    return (f"{band:.1f} % in its band ({_band_label(c['band'])}), {overall}"
            if band is not None else overall)


def heldout_text(c: dict) -> str:
    """What the test flights alone say of a row's shrink (`heldout`): its p value on their
    blocks and, when the shrink is below the smallest one they resolve, that it is within
    their noise and how many test flights would settle it."""
    h = c.get("heldout")
    if h is None:
        return ""
    out = f"; on the test flights alone p = {h['p']:.2g} over their {h['blocks']} blocks"
    if h["within_noise"]:
        out += (f"; within the noise of these flights (the smallest overall shrink their "
                f"blocks resolve is {h['detection_limit_pct']:.1f} %)")
        if h["flights_to_settle"]:
            out += (f": about {h['flights_to_settle']} test flights like these would settle "
                    "it")
    return out


def flights_line(d: Diagnosis) -> str:
    """Which flights chose the effect and which scored its shrink, truthfully: the selection
    is a cross-fit over every flight, the test flights among them."""
    n = len(d.train) + len(d.test)
    return (f"  flights: the selection (p, confidence, gains, the confidence set) is a cross-fit "
            f"over all {n} flights, each scored by a model fitted on others; the test flights "
            "take part, so they are not unseen by it (swapping training and test changes it "
            "little). The shrinks are of the test flights' load "
            f"error, the model re-fitted on the {len(d.train)} training flight"
            f"{'s' if len(d.train) != 1 else ''} only")


def _confidence_text(c: float) -> str:
    return "> 99.9 %" if c > 0.999 else f"{100 * c:.1f} %"


def _convergence_caution(sim: dict) -> str:
    """The caution on the simulated shrink when an output-error fit stopped at its step limit:
    the baseline's (which lacks the effect) makes its error, and so the shrink, too large; the
    augmented model's makes the shrink too small."""
    if sim.get("converged", True):
        return ""
    base = sim.get("converged_baseline", False)
    aug = sim.get("converged_augmented", False)
    if not base and aug:
        return ("; CAUTION: the model without the effect did not settle in its output-error "
                "fit, as a model that lacks what the flights show often does, so the shrink may "
                "be overstated: read it as an upper bound")
    if base and not aug:
        return ("; CAUTION: the model with the effect did not settle in its output-error fit, "
                "so the shrink may be understated: read it as a lower bound")
    return ("; CAUTION: neither model settled in its output-error fit: read the shrink as "
            "rough")


def _explanation_text(names: list[str]) -> str:
    return " + ".join(names) if names else "none"


def confidence_set_line(d: Diagnosis) -> str | None:
    """The confidence set in words: "X, or Y: these flights cannot tell them apart" when it
    holds more than one explanation; `None` when it holds one (or none was built)."""
    kept = d.confidence_set
    if len(kept) < 2:
        return None
    names = ", or ".join(_explanation_text(x["explanation"]) for x in kept)
    detail = "; ".join(f"{_explanation_text(x['explanation'])} {x['gain_pct']:.1f} %, "
                       f"p = {x['p_value']:.2g}" for x in kept)
    line = (f"  {names}: these flights cannot tell them apart (the model confidence set of the "
            f"explanations at {100 * d.settings.get('confidence_level', 0.1):g} %; gain: the "
            "typical drop of a 1 s block's load error variance in its effects' bands, "
            "cross-fit over all flights; and MCS p value: "
            f"{detail})")
    nxt = d.next_flight
    if nxt is not None:
        a, b = nxt["tell_apart"]
        where = nxt.get("input")
        line += (f"\n  ambiguous between {a} and {b}: fly {where} next (the input designed on "
                 "both fitted models to tell them apart, "
                 f"{_discrimination_text(nxt)}), then diagnose again with it among the test "
                 "flights" if where else
                 f"\n  ambiguous between {a} and {b}: fly the input of `fwid design "
                 "--discriminate` on this diagnosis's folder next"
                 + (f" (not designed here: {nxt['failed']})" if nxt.get("failed") else ""))
    return line


def _discrimination_text(nxt: dict) -> str:
    """The designed input's expected difference against a 3211's, in words."""
    c = nxt.get("criterion", {})
    ratio = c.get("ratio")
    return (f"expected difference {c.get('designed', float('nan')):.3g}, "
            + (f"{ratio:.2f}x a 3211's" if ratio is not None else "a 3211's diverges"))


def detection_line(d: Diagnosis) -> str | None:
    """The smallest gain these flights find with 80 % power and the flights a 3 % and a 5 %
    gain need (`diagnosis.json`'s `detection`); `None` without the block."""
    det = d.detection
    if det is None:
        return None
    n = det["flights"]
    need = [(g, m) for g, m in det["flights_for"].items() if m is not None]
    never = [g for g, m in det["flights_for"].items() if m is None]
    return (f"  detection: the smallest gain these {n} flights ({det['train_flights']} training"
            f" + {det['test_flights']} test, all scored by the cross-fit) detect with "
            f"{100 * det['power']:.0f} % power: {det['limit_pct']:.1f} %; "
            + "; ".join(f"a {g} % gain needs {m} flights" for g, m in need)
            + (f"; a {' or '.join(never)} % gain: never (at most the "
               f"{det['min_gain_pct']:g} % that counts)" if never else "")
            + " (flights of this kind; the limit falls like 1/sqrt(flights) down to "
            f"{det['min_gain_pct']:g} %)")


def _manoeuvre_text(tm: dict) -> str:
    """The held-out error in the manoeuvres against steady flight (`by_time` of the gap map),
    or that the flights hold no steady flight to compare with: the control moves from their
    first sample on (a closed-loop flight, or flights cut after their first input)."""
    ratio = tm["manoeuvre_to_steady"]
    if not np.isfinite(ratio):
        return "no steady flight before the first input to compare the manoeuvres with"
    return f"{ratio:.1f}x as large in the manoeuvres as in steady flight"


def _as_red(after: float, disturbance: dict) -> str:
    """How red an explanation left the baseline's held-out residual, beside how red it was."""
    return f"about as red ({after:.1f}, from {disturbance['redness']:.1f})"


def diagnosis_summary(d: Diagnosis) -> str:
    """A summary a person reads in ten seconds: the verdict, where the gap is, the shrink."""
    loc = d.localisation
    # the loads to talk about: those the verdict affects, else the manoeuvre axis's own
    own = [ld for ld in loc["by_output"] if ld in AXIS_LOADS[d.axis]]
    focus = d.lead["affected"] if d.lead is not None else own
    worst = max(focus or loc["by_output"], key=lambda ld: loc["by_output"][ld]["unexplained_pct"])
    bands = loc["by_band"][worst]
    top_band = max(bands, key=bands.get)
    tm = loc["by_time"][worst]
    st = loc["by_state"][worst]
    lines = [
        (f"fwid diagnose ({d.axis}): {len(d.train)} training, {len(d.test)} test flights, "
        f"{len(d.folds)} scoring blocks"),
        flights_line(d),
        f"  where the model misses: most in {worst}, {bands[top_band]:.0f} % of its held-out "
        f"error at {_band_label(top_band)}; " + _manoeuvre_text(tm)
        + (f"; growing with {st['top']} ({st['top_spread']:.1f}x across its range)"
           if st["top"] else ""),
    ]
    if d.verdict == "none":
        lim = [c["detection_limit_pct"] for c in d.candidates]
        lines.append("  VERDICT: none (no candidate effect improves the held-out fit "
                     "significantly; with 80 % power the cross-fit would have seen a drop of "
                     "the load error variance in the effect's band of "
                     f"{min(lim):.1f}-{max(lim):.1f} %, see 'smallest gain seen')")
    elif d.verdict == "random-disturbance":
        dist = d.disturbance
        size = ", ".join(f"{ld} {v:.3g}" for ld, v in dist["rms"].items())
        u, red = d.unexplained, dist.get("leaves_red")
        if red:
            names = " + ".join(red["effects"])
            why = (f"{names} predicts part of the held-out error but leaves it "
                   f"{_as_red(red['redness_after'], dist)}: it tracks what the disturbance did "
                   "to the states, so it is not named")
        elif u:
            why = (f"the {u['probe']} probe was selected (p = {u['p']:.2g}) but leaves it "
                   f"{_as_red(u['redness_after'], dist)}: it tracks what the disturbance did; "
                   "no catalogue effect explains it")
        else:
            why = "no catalogue effect or probe explains the held-out error"
        lines.append(f"  VERDICT: random-disturbance: {why}; the error is red (low/high-"
                     f"frequency PSD ratio {dist['redness']:.1f} >= {dist['red_min']:g}), as "
                     f"gusts or process noise make it; cycle-averaged residual RMS {size}; a "
                     "filter-error fit models it")
        if d.process_noise is not None:
            lines.append("  " + _process_noise_line(d.process_noise))
        if (d.states or {}).get("reconstructed") != "all":
            lines.append("  It may be process noise (a disturbance the vehicle felt) or coloured "
                         "errors in user-supplied states (a filter's lag, a gyro bias walk, "
                         "smoothed velocities): these flights cannot tell them apart. "
                         "Reconstructing the states from the raw recordings (fwid reconstruct) "
                         "removes that doubt")
    elif d.verdict == "unexplained":
        u = d.unexplained
        drv = ", ".join(f"{x['signal']} {x['share_pct']:.0f} %" for x in u["drivers"])
        lines.append(f"  VERDICT: unexplained: the held-out error of {'/'.join(u['affected'])} "
                     f"is predictable from the measured signals ({u['description']}"
                     + (f", {u['variant']}" if u["variant"] else "")
                     + f"; p = {u['p']:.2g}), but no catalogue effect explains it better; "
                     f"drivers: {drv}; adding it shrinks the test flights' RMS error of "
                     f"{'/'.join(u['affected'])} {u['test_shrink_pct']:.1f} % over all "
                     "frequencies" + heldout_text(d.lead))
    else:
        c = d.candidate(d.verdict)
        change = ", ".join(
            f"{ld} {c['test_rms_before'][ld]:.3g} -> {c['test_rms_after'][ld]:.3g}"
            for ld in c["affected"])
        lines.append(f"  VERDICT: {d.verdict}"
                     + (f" ({c['variant']})" if c["variant"] else "")
                     + f", selection confidence {_confidence_text(c['confidence'])} (cross-fit "
                     f"over all flights: a 1 s block's load error variance in its band drops "
                     f"{c['evidence']['heldout_gain_pct']:.1f} % typically)")
        lines.append(f"  on the test flights, re-fitted on the training flights only: the RMS "
                     f"error of {'/'.join(c['affected'])} shrinks {_shrink_text(c)} ({change})"
                     + heldout_text(c))
        red = (d.disturbance or {}).get("leaves_red")
        if red:  # a later entry tracked a disturbance: say so beside the verdict
            lines.append(f"  beside it, a disturbance: {' + '.join(red['effects'])} would cut "
                         "more of the held-out error but leaves it "
                         f"{_as_red(red['redness_after'], d.disturbance)}: it tracks what gusts "
                         "or process noise did to the states, so it is not named")
    det = detection_line(d)
    if det:
        lines.append(det)
    st = provenance_text(d.states)
    if st:
        lines.append(f"  states: {st}")
    cs = confidence_set_line(d)
    if cs:
        lines.append(cs)
    for e in d.effects if d.verdict == "unexplained" else d.effects[1:]:
        without = [x for x in d.confidence_set if e["effect"] not in x["explanation"]]
        lines.append(f"  and also: {e['effect']}"
                     + (f" ({e['variant']})" if e["variant"] else "")
                     + f", p = {e['p']:.2g}: the test flights' RMS error of "
                     f"{'/'.join(e['affected'])} shrinks a further {e['shrink_pct']:.1f} %"
                     + (f" (the confidence set also keeps "
                        f"{_explanation_text(without[0]['explanation'])} without it: these "
                        "flights cannot tell whether it is there)" if without else ""))
    for e in (d.unexplained or {}).get("then", []) if not d.effects else []:
        # chosen (the table says so) but after the probe: not named, and why
        lines.append(f"  then, after the {d.unexplained['probe']} probe: {e['effect']}"
                     + (f" ({e['variant']})" if e["variant"] else "")
                     + f", p = {e['p']:.2g}, a further {e['shrink_pct']:.1f} % on "
                     f"{'/'.join(e['affected'])}; not named: selected after structure outside "
                     "the catalogue, it may only echo it")
    if d.unexplained is not None and d.verdict not in ("unexplained", "random-disturbance"):
        u = d.unexplained
        lines.append(f"  and unexplained structure left: {u['description']}, p = {u['p']:.2g}, "
                     f"driven by {u['drivers'][0]['signal']}: a further "
                     f"{u['test_shrink_pct']:.1f} % on {'/'.join(u['affected'])}")
    sim = d.simulation
    if sim is not None and sim.get("failed"):
        lines.append(f"  in simulation: not measured: the block failed ({sim['failed']}); the "
                     "verdict and the load scores above do not depend on it")
    elif sim is not None and sim.get("message"):
        lines.append(f"  in simulation: {sim['message']}")
    elif sim is not None:
        change = ", ".join(f"{k} {sim['test_rms_before'][k]:.3g} -> {sim['test_rms_after'][k]:.3g}"
                           for k in sim["states"])
        lines.append(
            "  in simulation: " + (f"with {' + '.join(sim['effects'])} in the EOM, re-fitted by "
                                   f"output error, the test flights' simulated states shrink "
                                   f"{sim['shrink_pct']:.1f} % ({change})"
                                   if sim["effects"] else f"nothing added (state RMS {change})")
            + (f"; not in the cycle-averaged EOM: {', '.join(sim['left_out'])}"
               if sim["left_out"] else "")
            + _convergence_caution(sim))
    if sim is not None and fixed_text(sim.get("fixed_bias_terms", {})):
        lines.append("  " + fixed_text(sim["fixed_bias_terms"]))
    lines.append("  each candidate added alone to the model, re-fitted on the training flights and "
                 "scored on the test flights:")
    lines.append(f"  {'candidate':<18} {'chosen':>6} {'p':>8} {'shrink in band %':>16} "
                 f"{'overall %':>9} {'smallest gain seen %':>20}")
    first = d.first_round or {}
    for k, c in enumerate(d.candidates + d.probes):
        if k == len(d.candidates):
            lines.append("  probes (outside the catalogue):")
        band = in_band_shrink(c)
        p = first.get(c["effect"], {}).get("p", c["p"])
        lines.append(
            f"  {c['effect']:<18} {('yes' if c['significant'] else 'no'):>6} {p:8.2g} "
            f"{(f'{band:.1f}' if band is not None else '-'):>16} {c['shrink_pct']:9.1f} "
            f"{c['detection_limit_pct']:20.1f}"
        )
    lines.append("  (chosen: kept by the forward selection; p: its test of the candidate alone, "
                 "cross-fit over all flights; shrink in band / overall: the drop of the test "
                 "flights' RMS error of the affected loads in the effect's band / over all "
                 "frequencies, re-fitted on the training flights only; smallest gain seen: the "
                 "drop of the load error variance in the band (typical 1 s block, cross-fit) "
                 "that the test detects with 80 % power. Details in diagnosis.json; how to read "
                 "them: the guide's page on the diagnosis)")
    return "\n".join(lines)


def plot_gap_map(d: Diagnosis, path: str | Path | None = None) -> Figure:
    """Where the held-out error lives (share of each load's residual energy by band; RMS by
    time; mean square over the bins of the most telling state) and what the verdict (or the
    best candidate) removes, per load."""
    loc = d.localisation
    loads = [ld for ld in loc["by_output"] if ld in AXIS_LOADS[d.axis]] or list(loc["by_output"])
    fig = Figure(figsize=(12, 7.5), layout="constrained")
    ax = fig.subplots(2, 2)

    heat = np.array([[loc["by_band"][ld][b] for b in BAND_NAMES] for ld in loads])
    im = ax[0, 0].imshow(heat, aspect="auto", cmap="magma_r", vmin=0, vmax=100)
    ax[0, 0].set_xticks(range(len(BAND_NAMES)), _BAND_LABELS)
    ax[0, 0].set_yticks(range(len(loads)),
                        [f"{ld} ({loc['by_output'][ld]['unexplained_pct']:.1f} %)" for ld in loads])
    for i in range(len(loads)):
        for j in range(len(BAND_NAMES)):
            ax[0, 0].text(j, i, f"{heat[i, j]:.0f}", ha="center", va="center", fontsize=7,
                          color="w" if heat[i, j] > 50 else "k")
    fig.colorbar(im, ax=ax[0, 0], label="% of residual energy")
    ax[0, 0].set_title("held-out error by load (% unexplained) and band")

    x = np.arange(len(loads))
    keys = (("steady_rms", "steady"), ("manoeuvre_rms", "manoeuvre"),
            ("after_input_rms", "<1 s after input"))
    for k, (key, label) in enumerate(keys):
        rel = [loc["by_time"][ld][key] / loc["by_output"][ld]["rms"] for ld in loads]
        ax[0, 1].bar(x + (k - 1) * 0.27, rel, 0.27, label=label)
    ax[0, 1].axhline(1.0, color="k", lw=0.8)
    ax[0, 1].set_xticks(x, loads)
    ax[0, 1].set_ylabel("RMS / overall RMS")
    ax[0, 1].set_title("held-out error in time")
    ax[0, 1].legend(fontsize=8)

    for ld in loads:
        st = loc["by_state"][ld]
        if st["top"]:
            rel = st["bins"][st["top"]]["relative_ms"]
            ax[1, 0].plot(range(1, len(rel) + 1), rel, "o-", label=f"{ld} vs {st['top']}")
    ax[1, 0].axhline(1.0, color="k", lw=0.8)
    ax[1, 0].set_xlabel("quantile bin of the state (low to high)")
    ax[1, 0].set_ylabel("mean square / overall")
    ax[1, 0].set_title("held-out error over the flight state\n(most telling state per load)",
                       fontsize=9)
    ax[1, 0].legend(fontsize=8)

    c = d.lead or d.candidates[0]
    before = [c["test_rms_before"][ld] for ld in loads]
    after = [c["test_rms_after"][ld] / b if b > 0 else 1.0 for ld, b in zip(loads, before)]
    ax[1, 1].bar(x, after, color=["C2" if ld in c["affected"] else "C7" for ld in loads])
    ax[1, 1].axhline(1.0, color="k", lw=0.8)
    ax[1, 1].set_xticks(x, loads)
    ax[1, 1].set_ylabel("held-out RMS after / before")
    what = ("verdict" if d.lead else "best candidate"
            + ("" if c["significant"] else " (not significant)"))
    ax[1, 1].set_title(f"{what}"
                       f": {c['effect']}\nheld-out RMS shrinks {_shrink_text(c)}", fontsize=9)
    ax[1, 1].set_ylim(0, 1.1)
    fig.suptitle(f"fwid diagnose ({d.axis}): verdict {d.verdict}")
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_gap_sim(d: Diagnosis, path: str | Path | None = None, flight: int = 0) -> Figure | None:
    """One test flight's cycle-averaged states: measured, the baseline's simulation and the
    augmented model's (the diagnosed effects in the EOM), both fitted on the training flights
    by output error. `None` without a simulation block."""
    if d.models is None:
        return None
    base = d.models.baseline.validation[flight]
    aug = d.models.augmented.validation[flight] if d.models.augmented is not None else None
    states = d.simulation["states"]
    fig = Figure(figsize=(11, 1.9 * len(states) + 0.6), layout="constrained")
    axs = fig.subplots(len(states), 1, sharex=True, squeeze=False)[:, 0]
    for ax, s in zip(axs, states):
        scale = 180.0 / np.pi if s in ("q", "p", "r", "theta", "phi") else 1.0
        unit = {"q": "deg/s", "p": "deg/s", "r": "deg/s", "theta": "deg", "phi": "deg"}.get(
            s, "m/s")
        ax.plot(base.t, scale * base.measured[s], "k", lw=1.0, label="measured")
        ax.plot(base.t, scale * base.simulated[s], "C3", lw=1.0,
                label=f"baseline (RMS {d.simulation['test_rms_before'][s] * scale:.3g})")
        if aug is not None:  # None too when the augmented model diverged
            ax.plot(aug.t, scale * aug.simulated[s], "C2", lw=1.0,
                    label=f"+ {' + '.join(d.simulation['effects'])} "
                          f"(RMS {d.simulation['test_rms_after'][s] * scale:.3g})")
        ax.set_ylabel(f"d{s} [{unit}]")
        ax.legend(fontsize=7, loc="upper right")
    axs[-1].set_xlabel("time [s]")
    shrink = d.simulation["shrink_pct"]
    fig.suptitle(f"fwid diagnose ({d.axis}): test flight {base.name}, simulated states; "
                 + (f"shrink {shrink:.1f} %" if shrink is not None else
                    "the simulation diverges (see simulation.message)"
                    if d.simulation.get("diverged") else
                    "the augmented model diverged (see simulation.message)"))
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def _process_noise_line(pn: dict) -> str:
    """One line on the `process_noise` block: the filter-error fit's F and whiteness."""
    if "message" in pn:
        return f"process noise: the filter-error fit failed ({pn['message']})"
    F = ", ".join(f"{s} {v:.3g}" for s, v in pn["F"].items())
    white = [k for k, w in pn["innovations_white"].items() if w]
    caution = ("" if pn["converged"] and 2 * len(white) >= len(pn["innovations_white"]) else
               "; CAUTION: the process noise does not account for the residual (the fit "
               f"{'did not converge' if not pn['converged'] else 'leaves its innovations coloured'}"
               "): the redness may come from the measurements (a filtered attitude, a "
               "drifting sensor) or from an effect outside the model, not from a disturbance "
               "of the flight; read the verdict as uncertain")
    return (f"process noise (baseline by filter error on the training flights, "
            f"{'converged' if pn['converged'] else 'NOT converged'}): F {F}; innovations white "
            f"on {len(white)}/{len(pn['innovations_white'])} outputs"
            + (f" ({', '.join(white)})" if white else "") + caution)


def write_diagnosis(d: Diagnosis, out: str | Path) -> list[str]:
    """Write what `fwid diagnose --out` writes into `out`: `diagnosis.json` (last, once the
    rest is written), `gap_map.png`, and with a simulation block `gap_sim.png` and the model
    with the diagnosed effect to carry on with (`augmented_model.json`, a `report.json` of
    its own, and `augmented_parameters.csv`). Returns the file names written."""
    from ._identification import identification_report
    from ._json import parameters_csv, write_json, write_text

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    plot_gap_map(d, path=out / "gap_map.png")
    written = ["diagnosis.json", "gap_map.png"]
    if d.models is not None:
        plot_gap_sim(d, path=out / "gap_sim.png")
        written.append("gap_sim.png")
        if d.models.augmented is not None:
            rep = identification_report(d.models.augmented)
            # what the diagnosis fixed (time constants, leads) and what the extra inputs are
            rep["diagnosed_effects"] = d.simulation["effects"]
            rep["prepared_inputs"] = d.simulation["prepared_inputs"]
            write_json(out / "augmented_model.json", rep)
            write_text(out / "augmented_parameters.csv", parameters_csv(rep["parameters"]))
            written += ["augmented_model.json", "augmented_parameters.csv"]
    write_json(out / "diagnosis.json", d.to_json())
    return written
