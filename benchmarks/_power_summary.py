"""Summary of `diagnosis_power.py` results: power vs strength per effect and flight count,
false alarms on clean and out-of-catalogue flights, the confusion matrix, two-effect
both-named rate, the SINDy peer beside fwid on the same cases (Markdown), and the power
curves (PNG)."""

from __future__ import annotations

import platform
from collections import Counter, defaultdict
from pathlib import Path
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)


#: Verdicts that name no catalogue effect.
NOT_NAMED = ("none", "unexplained", "random-disturbance")
#: The verdict each out-of-catalogue effect should get (deterministic structure is
#: `unexplained`, gusts a `random-disturbance`).
OUT_VERDICT = {"turbulence": "random-disturbance", "cg-offset": "unexplained",
               "battery-sag": "unexplained"}


def right(r: dict) -> bool | None:
    """Whether a case got the right answer (`None`: no answer, an error).

    single: the verdict is the injected effect; clean: `none`; out of catalogue: no catalogue
    name (`none`, `unexplained` or `random-disturbance`: no false alarm); pair: both effects
    named (in `effects`, or the verdict and nothing else known when the result has no
    `effects`)."""
    if "verdict" not in r:
        return None
    named = r.get("effects") or ([r["verdict"]] if r["verdict"] != "none" else [])
    return _scored(r, r["verdict"], named)


def _scored(r: dict, verdict: str, named) -> bool:
    """Whether `verdict` (pairs: the effects `named`) answers case `r` (`right`)."""
    if r["kind"] == "single":
        return verdict == r["effect"]
    if r["kind"] == "clean":
        return verdict == "none"
    if r["kind"] == "out":
        return verdict in NOT_NAMED
    return set(r["effect"].split("+")) <= set(named)


def extras(results) -> list[str]:
    """Single effects named right with more effects after them."""
    rows = [r for r in results if r["kind"] == "single" and right(r)]
    more = [r for r in rows if len(r.get("effects") or []) > 1]
    named = Counter(e for r in more for e in r["effects"][1:])
    return [f"Right single verdicts: {len(rows)}; with a further (spurious) effect: "
            f"{len(more)}. Further effects named: "
            + (", ".join(f"{e} {k}" for e, k in named.most_common()) or "none") + "."]


def _frac(rows) -> str:
    ok = [right(r) for r in rows if right(r) is not None]
    return f"{sum(ok)}/{len(ok)}" if ok else "-"


def _rate(rows) -> float | None:
    ok = [right(r) for r in rows if right(r) is not None]
    return sum(ok) / len(ok) if ok else None


def power_table(results, by: str = "effect") -> list[str]:
    """Rows (effect or effect/form) x flight count, columns strengths: right / cases."""
    single = [r for r in results if r["kind"] == "single"]
    strengths = sorted({r["strength"] for r in single})
    key = (lambda r: r["effect"]) if by == "effect" else (lambda r: f"{r['effect']} / {r['form']}")
    lines = [f"| {by} | flights | " + " | ".join(f"s={s:g}" for s in strengths) + " | all |",
             "|---|---|" + "---:|" * (len(strengths) + 1)]
    groups = defaultdict(list)
    for r in single:
        groups[(key(r), r["n"])].append(r)
    for (k, n), rows in sorted(groups.items()):
        cells = [_frac([r for r in rows if r["strength"] == s]) for s in strengths]
        lines.append(f"| {k} | {n}+{n} | " + " | ".join(cells) + f" | {_frac(rows)} |")
    return lines


def confusion(results) -> list[str]:
    verdicts = sorted({r["verdict"] for r in results if "verdict" in r} | {"none"})
    rows = defaultdict(Counter)
    for r in results:
        if "verdict" in r and r["kind"] != "pair":
            rows[r["effect"]][r["verdict"]] += 1
    lines = ["| injected \\ verdict | " + " | ".join(verdicts) + " |",
             "|---|" + "---:|" * len(verdicts)]
    for e in sorted(rows):
        lines.append(f"| {e} | " + " | ".join(str(rows[e].get(v, 0)) for v in verdicts) + " |")
    return lines


def false_alarms(results) -> list[str]:
    """Clean and out-of-catalogue cases: false alarms (a catalogue name) and
    whether the verdict is the one expected (`none` / `OUT_VERDICT`)."""
    lines = ["| injected | flights | false alarms (a catalogue name) | expected verdict | cases |"
             " verdicts |", "|---|---|---:|---:|---:|---|"]
    null = [r for r in results if r["kind"] in ("clean", "out") and "verdict" in r]

    def expected(r):
        return r["verdict"] == OUT_VERDICT.get(r["effect"], "none")

    for (e, n), rows in sorted(Counter((r["effect"], r["n"]) for r in null).items()):
        rr = [r for r in null if r["effect"] == e and r["n"] == n]
        seen = Counter(r["verdict"] for r in rr)
        lines.append(f"| {e} | {n}+{n} | {sum(r['verdict'] not in NOT_NAMED for r in rr)} | "
                     f"{sum(expected(r) for r in rr)} | {len(rr)} | "
                     + ", ".join(f"{v} {k}" for v, k in seen.most_common()) + " |")
    tot = sum(r["verdict"] not in NOT_NAMED for r in null)
    lines.append(f"| **all** | | {tot} | {sum(expected(r) for r in null)} | {len(null)} | |")
    return lines


#: The four effects of the original catalogue (the README's verdict table before
#: `unsteady-aero`, `time-offset` and `flap-frequency` were added).
ORIGINAL_FOUR = {"flap-coupling", "nonlinear-aero", "lon-lat-coupling", "actuator-dynamics"}
UNSTEADY = "unsteady-aero"


def catalogue_pairs(rows) -> list[str]:
    """The pairs scored against the original catalogue: both named (`right`) for
    pairs of its four effects; for pairs with `unsteady-aero` (outside that catalogue),
    whether the other effect is named (as for a single effect beside a disturbance)."""
    def parts(r):
        return set(r["effect"].split("+"))

    four = [r for r in rows if parts(r) <= ORIGINAL_FOUR]
    rest = [r for r in rows if UNSTEADY not in parts(r)]
    lag = [r for r in rows if UNSTEADY in parts(r)]
    other = [r for r in lag if parts(r) - {UNSTEADY} <= set(r["effects"])]
    n_ok = sum(map(right, rest)) + len(other)
    return ["Scored against the original four-effect catalogue (an unsteady lag outside it):",
            f"- pairs of the original four effects, both named: "
            f"{sum(map(right, four))}/{len(four)};",
            f"- pairs without `{UNSTEADY}`, both named: {sum(map(right, rest))}/{len(rest)};",
            f"- pairs with `{UNSTEADY}`, the other effect named: {len(other)}/{len(lag)}"
            f" (both: {sum(map(right, lag))});",
            f"- all pairs so scored: {n_ok}/{len(rows)}."]


def pairs(results) -> list[str]:
    rows = [r for r in results if r["kind"] == "pair" and "verdict" in r]
    lines = ["| effects | forms | axis | verdict | effects named | both |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['effect']} | {r['form']} | {r['axis']} | {r['verdict']} | "
                     f"{', '.join(r.get('effects') or []) or '-'} | {'yes' if right(r) else 'no'} |")
    lines.append(f"\nBoth named: {_frac(rows)}.")
    # an actuator delay or lag and a late log of the same deflection are one net shift of it
    shift = {"actuator-dynamics", "time-offset"}
    rest = [r for r in rows if set(r["effect"].split("+")) != shift]
    lines.append(f"Without `actuator-dynamics+time-offset` (both act as one shift of the same "
                 f"deflection): {_frac(rest)}.")
    lines += ["", *catalogue_pairs(rows)]
    lines += ["", "| effect | pairs with it | both named |", "|---|---:|---:|"]
    for e in sorted({x for r in rows for x in r["effect"].split("+")}):
        with_e = [r for r in rows if e in r["effect"].split("+")]
        lines.append(f"| {e} | {len(with_e)} | {sum(right(r) for r in with_e)} |")
    return lines


def _named(explanation: list[str]) -> frozenset[str]:
    """The catalogue entries of an explanation of the confidence set (probes left out)."""
    from fwid.diagnosis import EFFECT_NAMES

    return frozenset(e for e in explanation if e in EFFECT_NAMES)


def set_score(r: dict) -> dict | None:
    """How a case's confidence set (`confidence_set`: explanations, best first) scores:
    `covered` (single: an explanation names the injected effect and no other entry; pair: one
    holds both), `holds` (an explanation names the injected effects, maybe with others),
    `decisive` (single: every explanation names the injected effect and no other),
    `decisive_wrong` (single: every explanation names the same catalogue entries, and they
    are not the injected effect), `alarm` (clean, out of catalogue: an explanation names an
    entry) and `best` (the best explanation's first effect as a verdict: a probe is
    `unexplained`, none `none`). `None` without a set."""
    kept = r.get("confidence_set")
    if not kept:
        return None
    named = [_named(x["explanation"]) for x in kept]
    first = kept[0]["explanation"]
    from fwid.diagnosis import EFFECT_NAMES

    best = "none" if not first else first[0] if first[0] in EFFECT_NAMES else "unexplained"
    truth = frozenset(r["effect"].split("+")) if r["kind"] in ("single", "pair") else None
    return {"covered": truth is not None and (truth in named if r["kind"] == "single"
                                              else any(truth <= n for n in named)),
            "holds": truth is not None and any(truth <= n for n in named),
            "decisive": r["kind"] == "single" and all(n == truth for n in named),
            "decisive_wrong": (r["kind"] == "single" and bool(named[0]) and named[0] != truth
                               and all(n == named[0] for n in named)),
            "alarm": r["kind"] in ("clean", "out") and any(named),
            "best": best, "size": len(kept)}


def set_table(results) -> list[str]:
    """Coverage, decisiveness, false alarms and pairs of the confidence set, per flight count
    (single effects at strength 1 and all strengths), beside the verdict's rate."""
    rows = [(r, set_score(r)) for r in results if "verdict" in r]
    rows = [(r, s) for r, s in rows if s is not None]
    if not rows:
        return ["(no confidence sets recorded)"]
    out = ["| cases | n | coverage | in an explanation | decisive | verdict right | "
           "best explanation right | mean set size |", "|---|---|---|---|---|---|---|---|"]

    def line(label, sel):
        if not sel:
            return
        n = len(sel)
        cov = sum(s["covered"] for _, s in sel)
        dec = sum(s["decisive"] for _, s in sel)
        holds = sum(s["holds"] for _, s in sel)
        ok = sum(bool(right(r)) for r, _ in sel)
        best = sum(s["best"] == r["effect"] for r, s in sel)
        size = sum(s["size"] for _, s in sel) / n
        out.append(f"| {label} | {n} | {cov}/{n} | {holds}/{n} | {dec}/{n} | {ok}/{n} | "
                   f"{best}/{n} | {size:.1f} |")

    single = [(r, s) for r, s in rows if r["kind"] == "single"]
    for n in sorted({r["n"] for r, _ in single}):
        line(f"single, strength 1, {n}+{n}",
             [(r, s) for r, s in single if r["n"] == n and r["strength"] == 1.0])
    line("single, all strengths", single)
    pairs_ = [(r, s) for r, s in rows if r["kind"] == "pair"]
    if pairs_:
        out += ["", f"Pairs: a kept explanation holds both effects in "
                f"{sum(s['covered'] for _, s in pairs_)}/{len(pairs_)} (both in `effects`: "
                f"{sum(bool(right(r)) for r, _ in pairs_)}/{len(pairs_)})."]
    quiet = [(r, s) for r, s in rows if r["kind"] in ("clean", "out")]
    if quiet:
        out += ["", f"False alarms: a catalogue name in the set of "
                f"{sum(s['alarm'] for _, s in quiet)}/{len(quiet)} clean and out-of-catalogue "
                f"cases (in the verdict: {sum(not right(r) for r, _ in quiet)}/{len(quiet)}; "
                f"the best explanation names one in "
                f"{sum(s['best'] not in NOT_NAMED for _, s in quiet)}/{len(quiet)})."]
    return out


#: The peers a results file may hold beside fwid (a record's key, the row's name).
PEERS = {"sindy": "SINDy (pysindy)"}


def peer_right(r: dict, who: str) -> bool | None:
    """Whether peer `who` got case `r` right, as `right` scores fwid (pairs: both effects among
    the families it keeps); `None` without its verdict."""
    p = r.get(who) or {}
    if "verdict" not in p:
        return None
    return _scored(r, p["verdict"], p.get("kept") or [])


def peer_table(results) -> list[str]:
    """fwid's row and each peer's on the same cases (those both answered): single effects at
    strength 1 with 6+6 flights (verdict right; the truth held: fwid's confidence set covers
    it, the peer keeps it among its families; decisive: nothing else kept), the same with 4+4,
    pairs (both named), false alarms (a catalogue name as the verdict of a clean or
    out-of-catalogue case), and the wall time per case."""
    out = []
    for who, label in PEERS.items():
        both = [r for r in results if "verdict" in r and peer_right(r, who) is not None]
        if not both:
            continue
        out += ["| method | single s=1 6+6: right | holds the truth | decisive | single s=1 4+4: "
                "right | pairs: both named | false alarms (clean + out) | wall s per case "
                "(median, mean) |", "|---|---|---|---|---|---|---|---|"]

        def frac(rows, ok):
            return f"{sum(map(ok, rows))}/{len(rows)}" if rows else "-"

        def sel(kind, n=None):
            return [r for r in both if r["kind"] == kind and (n is None or r["n"] == n)
                    and (kind != "single" or r["strength"] == 1.0)]

        s6, s4, pr = sel("single", 6), sel("single", 4), sel("pair")
        quiet = [r for r in both if r["kind"] in ("clean", "out")]

        def fwid_holds(r):
            s = set_score(r)
            return bool(s and s["covered"])

        def fwid_decisive(r):
            s = set_score(r)
            return bool(s and s["decisive"])

        def kept(r):
            return r[who].get("kept") or []

        def walls(vals):
            vals = sorted(vals)
            return (f"{vals[len(vals) // 2]:.1f}, {sum(vals) / len(vals):.1f}" if vals else "-")

        rows = {
            "fwid": (lambda r: bool(right(r)), fwid_holds, fwid_decisive,
                     lambda r: r["verdict"] not in NOT_NAMED, [r["wall_s"] for r in both
                                                                if "wall_s" in r]),
            label: (lambda r: bool(peer_right(r, who)), lambda r: r["effect"] in kept(r),
                    lambda r: kept(r) == [r["effect"]],
                    lambda r: r[who]["verdict"] not in NOT_NAMED,
                    [r[who]["wall_s"] for r in both if "wall_s" in r[who]]),
        }
        for name, (ok, holds, decisive, alarm, wall) in rows.items():
            out.append(f"| {name} | {frac(s6, ok)} | {frac(s6, holds)} | {frac(s6, decisive)} | "
                       f"{frac(s4, ok)} | {frac(pr, ok)} | {frac(quiet, alarm)} | "
                       f"{walls(wall)} |")
        failed = sum(1 for r in results if "verdict" in r and "error" in (r.get(who) or {}))
        out += ["", f"{len(both)} cases with both verdicts (the same flights for both)"
                + (f"; the peer failed on {failed}" if failed else "") + "."]
    return out or ["(no peer ran: `--no-peer`)"]


def figure(results, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    single = [r for r in results if r["kind"] == "single"]
    effects = sorted({r["effect"] for r in single})
    if not effects:
        return
    fig, axs = plt.subplots(1, len(effects), figsize=(3.2 * len(effects), 3.3), sharey=True,
                            squeeze=False)
    counts = sorted({r["n"] for r in single})
    strengths = sorted({r["strength"] for r in single})
    for ax, e in zip(axs[0], effects):
        for i, n in enumerate(counts):
            rows = [r for r in single if r["effect"] == e and r["n"] == n]
            ss = sorted({r["strength"] for r in rows})
            ps = [_rate([r for r in rows if r["strength"] == s]) for s in ss]
            pts = [(s, p) for s, p in zip(ss, ps) if p is not None]
            if pts:
                ax.plot(*zip(*pts), "o-", color=f"C{i}")
        ax.set_xscale("log", base=2)
        ax.set_xticks(strengths, [f"{s:g}" for s in strengths])
        ax.set_title(e, fontsize=9)
        ax.set_xlabel("strength")
        ax.set_ylim(-0.05, 1.05)
        ax.axhline(0.9, color="grey", lw=0.5, ls=":")
    axs[0][0].set_ylabel("right verdict")
    handles = [plt.Line2D([], [], color=f"C{i}", marker="o") for i in range(len(counts))]
    fig.legend(handles, [f"{n}+{n} flights" for n in counts], loc="lower center",
               ncol=len(counts), fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=110, metadata={"Description": _provenance.header(_provenance.provenance())})
    plt.close(fig)


def _count(scores: list[dict], key: str) -> str:
    """`k/n` (and the per cent) of the `set_score`s whose `key` holds."""
    k = sum(bool(s.get(key)) for s in scores)
    return f"{k}/{len(scores)}" + (f" ({100 * k / len(scores):.0f} %)" if scores else "")


def truth_gain_table(results, promised=None, weak: float = 4.0) -> list[str]:
    """Single cases split by their truth's own held-out gain at `weak` %: right verdicts on
    each side; for the weak ones fwid's flights for that gain; and, with `promised` (the
    `--promise` reruns), how often the effect was named at those flights."""
    rows = [r for r in results if r.get("kind") == "single" and "truth_gain_pct" in r]
    if not rows:
        return ["(no truth gains recorded)"]
    strong = [r for r in rows if r["truth_gain_pct"] >= weak]
    low = [r for r in rows if r["truth_gain_pct"] < weak]
    out = ["Single effects (each case's truth gain: its effect's own first-round held-out "
           "gain). Covered: an explanation of the set is the truth alone; decisive and right: "
           "every kept explanation is; decisive and wrong: every kept explanation names the "
           "same other entries.", "",
           "| truth's held-out gain | n | cases | verdict right | covered | decisive and right "
           "| decisive and wrong | fwid's limit % (median) |",
           "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, rr in ((f">= {weak:g} %", strong), (f"< {weak:g} %", low)):
        for n in sorted({r["n"] for r in rr}):
            sel = [r for r in rr if r["n"] == n]
            sc = [set_score(r) or {} for r in sel]
            lim = sorted(r["detection"]["limit_pct"] for r in sel if r.get("detection"))
            out.append(f"| {name} | {n}+{n} | {len(sel)} | {_frac(sel)} | "
                       f"{_count(sc, 'covered')} | {_count(sc, 'decisive')} | "
                       f"{_count(sc, 'decisive_wrong')} | "
                       + (f"{lim[len(lim) // 2]:.1f} |" if lim else "- |"))
    two = [r for r in results if r.get("kind") == "pair" and "truth_gain_pct" in r]
    if two:
        out += ["", "Pairs, split by the smaller of their two effects' own gains (both kept: "
                "an explanation of the set holds both; both named: both in `effects`):", "",
                "| smaller truth gain | cases | both kept | both named |", "|---|---:|---:|---:|"]
        for name, rr in ((f">= {weak:g} %", [r for r in two if r["truth_gain_pct"] >= weak]),
                         (f"< {weak:g} %", [r for r in two if r["truth_gain_pct"] < weak])):
            sc = [set_score(r) or {} for r in rr]
            out.append(f"| {name} | {len(rr)} | {_count(sc, 'covered')} | {_frac(rr)} |")
    never = [r for r in low if r.get("flights_for_truth") is None]
    out += ["", f"Weak cases: {len(low)}; fwid says no number of flights finds the gain of "
            f"{len(never)} (at or below the smallest gain that counts, or negative).", "",
            "| effect | form | flights | truth gain % | flights fwid says | rerun: named |",
            "|---|---|---|---:|---:|---|"]
    by_key = {(p["effect"], p["form"], p["strength"], p["n"], p["seed"]): p
              for p in promised or []}
    for r in low:
        p = by_key.get((r["effect"], r["form"], r["strength"], r["n"], r["seed"]))
        res = "-" if p is None else (p.get("skipped") or p.get("error") or
                                     ("yes" if p["found"] else f"no ({p['verdict']})"))
        out.append(f"| {r['effect']} | {r['form']} | {r['n']}+{r['n']} | "
                   f"{r['truth_gain_pct']:.2f} | {r.get('flights_for_truth') or 'never'} | "
                   f"{res} |")
    if promised:
        ran = [p for p in promised if "found" in p]
        hit = sum(p["found"] for p in ran)
        out += ["", f"The promise (named at fwid's flight count, target >= 80 %): {hit}/"
                f"{len(ran)}" + (f" ({100 * hit / len(ran):.0f} %)" if ran else "")
                + f"; {len(promised) - len(ran)} skipped (too many flights)."]
    return out


def summarise(results: list[dict], stem: Path, note: str = "",
              promised: list[dict] | None = None) -> str:
    """Write `stem.md` and `stem.png`; return the Markdown."""
    stem = Path(stem)
    errors = [r for r in results if "error" in r]
    walls = sorted(r["wall_s"] for r in results if "wall_s" in r)
    md = [f"# fwid diagnose: power on the randomised benchmark ({stem.name})", "",
          f"{len(results)} cases ({len(errors)} without a verdict: "
          f"{dict(Counter(r['error'].split(':')[0] for r in errors))}). {note}. "
          f"Machine: {platform.platform()}.",
          (f"Diagnosis wall time: median {walls[len(walls) // 2]:.1f} s, max {walls[-1]:.1f} s."
           if walls else ""), "",
          "Right verdict: the injected effect (single), `none` (clean, out of catalogue), both "
          "effects in `effects` (pairs). Cells: right / cases.", "",
          "## Power per effect", "", *power_table(results, "effect"), "",
          "## Power per form", "", *power_table(results, "form"), "",
          "## False alarms (clean and out-of-catalogue flights)", "", *false_alarms(results), "",
          "## Confusion matrix (single effects, clean, out of catalogue)", "", *confusion(results),
          "", "## Two effects at once", "", *pairs(results), "",
          "## Spurious further effects", "", *extras(results), "",
          "## The confidence set of explanations", "", *set_table(results), "",
          "## A peer beside fwid (the same flights)", "", *peer_table(results), "",
          "## The detection limit's promise (split by the truth's held-out gain)", "",
          *truth_gain_table(results, promised), "",
          f"![power curves]({stem.name}.png)", ""]
    text = "\n".join(md)
    stem.with_suffix(".md").write_text(_provenance.markdown(text))
    figure(results, stem.with_suffix(".png"))
    return text
