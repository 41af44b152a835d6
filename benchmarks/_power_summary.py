"""Summary of `diagnosis_power.py` results: power vs strength per effect and flight count,
false alarms on clean and out-of-catalogue flights, the confusion matrix, two-effect
both-named rate (Markdown), and the power curves (PNG)."""

from __future__ import annotations

import platform
from collections import Counter, defaultdict
from pathlib import Path
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)


#: Verdicts that name no catalogue effect.
NOT_NAMED = ("none", "unexplained", "random-disturbance")
#: The verdict each out-of-catalogue effect should get (issue 16: deterministic structure is
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
    if r["kind"] == "single":
        return r["verdict"] == r["effect"]
    if r["kind"] == "clean":
        return r["verdict"] == "none"
    if r["kind"] == "out":
        return r["verdict"] in NOT_NAMED
    named = set(r.get("effects") or ([r["verdict"]] if r["verdict"] != "none" else []))
    return set(r["effect"].split("+")) <= named


def tentative_named(r: dict) -> set[str]:
    """The effects of a result named after the first as `tentative` (`effects_detail`; for a
    record written before the flag existed, from its recorded `rounds` by the same rule,
    `fwid.diagnosis._selection.tentative`)."""
    detail = r.get("effects_detail") or []
    if detail and "tentative" in detail[0]:
        return {e["effect"] for e in detail if e.get("tentative")}
    from fwid.diagnosis._selection import tentative

    rounds, named = r.get("rounds") or [], r.get("effects") or []
    if len(named) < 2 or not rounds:
        return set()
    gain = {rd["added"]: rd["candidates"][rd["added"]]["gain_pct"] for rd in rounds
            if rd["added"]}
    return {e for e in named[1:] if tentative(gain[named[0]], gain[e])}


def firmly_right(r: dict) -> bool | None:
    """`right`, counting only the effects named firmly (not `tentative`) for a pair."""
    ok = right(r)
    if r["kind"] != "pair" or not ok:
        return ok
    return not set(r["effect"].split("+")) & tentative_named(r)


def extras(results) -> list[str]:
    """Single effects named right with more effects after them: firm and tentative."""
    rows = [r for r in results if r["kind"] == "single" and right(r)]
    more = [r for r in rows if len(r.get("effects") or []) > 1]
    firm = [r for r in more if set(r["effects"][1:]) - tentative_named(r)]
    named = Counter(e for r in more for e in r["effects"][1:])
    return [f"Right single verdicts: {len(rows)}; with a further (spurious) effect: "
            f"{len(more)}, of which {len(firm)} named firmly and {len(more) - len(firm)} only "
            f"`tentative`. Further effects named: "
            + (", ".join(f"{e} {k}" for e, k in named.most_common()) or "none") + "."]


def near_tie(r: dict) -> bool | None:
    """Was the verdict's effect or probe a near tie (`fwid.diagnosis._selection.near_tie`)?
    The record's own `near_tie` (`None` where no row carries the flag: `none`,
    `random-disturbance`); for an older record, from the first effect's row or the
    `unexplained` record, or, written before the flag existed, from its first recorded round
    by the same rule. `None`: nothing was selected."""
    from types import SimpleNamespace as ns

    from fwid.diagnosis._catalogue import CATALOGUE
    from fwid.diagnosis._selection import MIN_GAIN, passes, runner_up
    from fwid.diagnosis._selection import near_tie as rule

    if "near_tie" in r:  # recorded as the user saw it
        return r["near_tie"]
    lead = (r.get("unexplained") if r.get("verdict") == "unexplained" else
            (r.get("effects_detail") or [None])[0])
    if lead is not None and "near_tie" in lead:
        return bool(lead["near_tie"])
    rounds = r.get("rounds") or []
    if not rounds or not rounds[0]["added"]:
        return None
    rd = rounds[0]
    rates = {e.name for e in CATALOGUE if e.rates}
    ev = {k: ns(p=v["p"], gain=v["gain_pct"] / 100) for k, v in rd["candidates"].items()}
    passing = {k: e for k, e in ev.items()
               if k == rd["added"] or passes(ns(rates=k in rates), e, rd["level"], MIN_GAIN)}
    return rule(runner_up(rd["added"], passing))


def near_ties(results) -> list[str]:
    """Right and wrong verdicts (single effects, clean, out of catalogue) with and without a
    near tie: whether the flag tells the verdicts to doubt."""
    rows = [(near_tie(r), right(r)) for r in results
            if r["kind"] != "pair" and right(r) is not None]
    out = ["| verdict | right | wrong | wrong share |", "|---|---:|---:|---:|"]
    for label, flag in (("near tie", True), ("no near tie", False)):
        ok = [x for f, x in rows if f is flag]
        bad = len(ok) - sum(ok)
        out.append(f"| {label} | {sum(ok)} | {bad} | "
                   + (f"{100 * bad / len(ok):.0f} % |" if ok else "- |"))
    return out


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
    """Clean and out-of-catalogue cases: false alarms (a catalogue name) and, per issue 16,
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


#: The catalogue issue 12 set its pair target on (CONTRACTS section 4); it lists an unsteady
#: aerodynamic lag among the disturbances outside the catalogue, which issue 16 later added.
CONTRACTS_FOUR = {"flap-coupling", "nonlinear-aero", "lon-lat-coupling", "actuator-dynamics"}
UNSTEADY = "unsteady-aero"


def catalogue_pairs(rows) -> list[str]:
    """The pairs scored against the catalogue as issue 12 wrote it: both named (`right`) for
    pairs of CONTRACTS' four effects; for pairs with `unsteady-aero` (outside that catalogue),
    whether the other effect is named (as for a single effect beside a disturbance)."""
    def parts(r):
        return set(r["effect"].split("+"))

    four = [r for r in rows if parts(r) <= CONTRACTS_FOUR]
    rest = [r for r in rows if UNSTEADY not in parts(r)]
    lag = [r for r in rows if UNSTEADY in parts(r)]
    other = [r for r in lag if parts(r) - {UNSTEADY} <= set(r["effects"])]
    n_ok = sum(map(right, rest)) + len(other)
    return ["Scored against issue 12's catalogue (an unsteady lag outside it):",
            f"- pairs of CONTRACTS' four effects, both named: {sum(map(right, four))}/{len(four)};",
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
    firm = sum(bool(firmly_right(r)) for r in rows)
    lines.append(f"Both named, neither `tentative`: {firm}/{len(rows)}.")
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


def summarise(results: list[dict], stem: Path, note: str = "") -> str:
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
          "## Near ties (a rival passing with at least `TIE_SHARE` of the verdict's gain)", "",
          *near_ties(results), "",
          f"![power curves]({stem.name}.png)", ""]
    text = "\n".join(md)
    stem.with_suffix(".md").write_text(_provenance.markdown(text))
    figure(results, stem.with_suffix(".png"))
    return text
