"""Terminal tables in the paper's layouts (Tables 1-6)."""

from __future__ import annotations

import numpy as np

from ._bounded import NOT_IDENTIFIABLE, STD_OVER_VALUE_MAX, identifiable
from ._numbers import fixed, score


#: The SI unit of each signal, as in report.json.
SI_UNITS = {"q": "rad/s", "p": "rad/s", "r": "rad/s", "theta": "rad", "phi": "rad", "psi": "rad",
            "alpha": "rad", "beta": "rad", "u": "m/s", "w": "m/s", "v": "m/s", "de": "rad",
            "dr": "rad", "X": "N", "Y": "N", "Z": "N", "L": "N m", "M": "N m", "N": "N m"}


def _chunks(seq, n):
    k = int(np.ceil(len(seq) / n))
    return [seq[i * k:(i + 1) * k] for i in range(n)]


def parameter_table(params: dict, *, columns: int = 3) -> str:
    """Table 1's layout: `param  value  |sigma|  100|sigma/value|`, in `columns` groups; a
    parameter that is not identifiable (`fwid.report._bounded.identifiable`) shows that
    instead of its numbers, named in a line below the table."""
    names = list(params)
    lost = [k for k in names
            if identifiable(params[k].get("value"), params[k].get("std")) is False]
    groups = _chunks(names, columns)
    head = "  ".join(f"{'param':<8}{'value':>11}{'|sigma|':>10}{'100|s/v|':>9}" for _ in groups)
    lines = [head, "-" * len(head)]
    for r in range(max(len(g) for g in groups)):
        cells = []
        for g in groups:
            if r < len(g):
                k = g[r]
                p = params[k]
                if k in lost:
                    cells.append(f"{k:<8}{'not identifiable':>30}")
                    continue
                std = p.get("std")
                rel = 100 * abs(std / p["value"]) if std is not None and p["value"] else float("nan")
                std = float("nan") if std is None else std
                cells.append(f"{k:<8}{p['value']:>11.3e}{std:>10.2e}{fixed(rel, 9)}")
            else:
                cells.append(" " * 38)
        lines.append("  ".join(cells).rstrip())
    if lost:
        which = (f"all {len(names)} parameters" if len(lost) == len(names)
                 else ", ".join(lost))
        lines.append(f"{NOT_IDENTIFIABLE}: {which} (|sigma| above "
                     f"{STD_OVER_VALUE_MAX:.0f} |value|, or not finite; the numbers are in "
                     "report.json)")
    return "\n".join(lines)


def metrics_table(metrics: dict, title: str = "") -> str:
    """Table 2's layout: output correlation, R^2, RMS (in the output's SI unit) and RMS as %
    of the output's measured range, per output; every number in a bounded width (an R2 far
    below zero as `<-1e3`, see `_numbers.py`); an output whose simulation diverged
    (`diverged_at_s`, `fwid.report._bounded.mark_diverged`) says when instead."""
    lines = [title] if title else []
    lines.append(f"{'output':<8}{'corr':>7}{'R2':>8}{'RMS':>11} {'unit':<6}{'% range':>8}")
    for k, m in metrics.items():
        if m.get("diverged_at_s") is not None:
            where = f" ({m['diverged_in']})" if m.get("diverged_in") else ""
            lines.append(f"{k:<8}  simulation diverged at t = {m['diverged_at_s']:.3g} s{where}")
            continue
        lines.append(f"{k:<8}{score(m['corr'], 7)}{score(m['r2'], 8)}{m['rms']:>11.3e} "
                     f"{SI_UNITS.get(k, ''):<6}{fixed(m['rms_pct'], 8)}")
    return "\n".join(lines)


def modes_table(modes: list[dict]) -> str:
    """Eigenvalues (Tables 3, 6) with each mode's frequency, damping or time constant."""
    lines = [f"{'eigenvalue':<24}{'mode':<12}{'wn [rad/s]':>11}{'zeta':>7}{'tau [s]':>9}"]
    for m in modes:
        re, im = m["eigenvalue"]
        re, im = fixed(re, 11, 4).strip(), fixed(im, 11, 4).strip()
        ev = f"{re} +/- {im}i" if m["kind"] == "oscillatory" else re
        if m["kind"] == "oscillatory":
            lines.append(f"{ev:<24}{'oscillatory':<12}{fixed(m['wn'], 11, 3)}"
                         f"{fixed(m['zeta'], 7, 3)}{'':>9}")
        else:
            lines.append(f"{ev:<24}{'aperiodic':<12}{'':>11}{'':>7}{fixed(m['tau'], 9, 3)}")
    return "\n".join(lines)


def spread_table(spread: dict, title: str = "") -> str:
    """The spread of the modes over flights fitted one by one (`modes_spread` of
    report.json): mean, sample std, min and max of the oscillatory mode's natural frequency
    and damping and of each aperiodic time constant."""
    lines = [title or f"mode spread over {spread['flights']} flights (each fitted alone):",
             f"{'':<14}{'mean':>10}{'std':>10}{'min':>10}{'max':>10}"]
    osc = spread.get("oscillatory")
    if osc:
        for key, label in (("wn", "wn [rad/s]"), ("zeta", "zeta")):
            lines.append(f"{label:<14}" + "".join(f"{osc[f'{key}_{s}']:>10.4g}"
                                                   for s in ("mean", "std", "min", "max")))
    for j, tau in enumerate(spread.get("aperiodic_tau", [])):
        lines.append(f"{f'tau {j + 1} [s]':<14}" + "".join(
            f"{tau.get(s, float('nan')):>10.4g}" for s in ("mean", "std", "min", "max")))
    return "\n".join(lines)


def warnings_lines(report: dict) -> list[str]:
    """The report's `warnings`, one `WARNING:` line each (none when there are none)."""
    return [""] + [f"WARNING: {w}" for w in report["warnings"]] if report.get("warnings") else []


def prior_bounds_lines(report: dict) -> list[str]:
    """One line each for the prior and the bounds a report's fits used (none without)."""
    out = []
    if report.get("prior"):
        out.append("prior (mean +- std): " + ", ".join(
            f"{k} {p['mean']:.4g} +- {p['std']:.3g}" for k, p in report["prior"].items()))
    if report.get("bounds"):
        def side(x):
            return "open" if x is None else f"{x:.4g}"

        out.append("bounds: " + ", ".join(
            f"{k} in [{side(b['low'])}, {side(b['high'])}]"
            + (f" (active at {b['at']})" if b["active"] else "")
            for k, b in report["bounds"].items()))
    return out


def identification_summary(report: dict) -> str:
    """The terminal summary of `fwid identify`: parameters, modes, metrics."""
    out = [f"fwid identify: model {report['model']}, flights: {', '.join(report['flights'])}"]
    if "summary" in report:
        out.append(f"({report['summary']})")
    out += ["", parameter_table(report["parameters"]), *prior_bounds_lines(report), "",
            modes_table(report["modes"]), ""]
    if "modes_spread" in report:
        out += [spread_table(report["modes_spread"]), ""]
    out.append(metrics_table(report["metrics"]["estimation"], "match with estimation data:"))
    if "validation" in report["metrics"]:
        out += ["", metrics_table(report["metrics"]["validation"], "match with validation data:")]
    return "\n".join(out + warnings_lines(report))


def _peak_summary(peaks: dict) -> list[str]:
    out = [f"{'flight':<22}{'signal':<7}" + "".join(f"{f'peak {i + 1} meas/model':>24}"
                                                    for i in range(3))]
    for name, d in peaks.items():
        for k, v in d.items():
            cells = "".join(f"{a:>11.3e}/{b:<10.3e}  " for a, b in zip(v["measured"], v["model"]))
            out.append(f"{name[:21]:<22}{k:<7}{cells}")
    return out


def flapping_summary(report: dict) -> str:
    """The terminal summary of `fwid identify --model flap|combined`."""
    out = [f"fwid identify: model {report['model']}, flights: {', '.join(report['flights'])}"]
    if "summary" in report:
        out.append(f"({report['summary']})")
    if report["model"] == "combined":
        out += ["", "cycle-averaged part (Section IV):",
                parameter_table(report["cycle_averaged"]["parameters"]), "",
                modes_table(report["cycle_averaged"]["modes"])]
        flap = report["flapping"]
    else:
        flap = report
    out += ["", f"flapping part, Eq. (12), {flap['harmonics']} harmonics (Table 7):",
            parameter_table(flap["parameters"])]
    out += ["", "flapping frequency [Hz] and phase offset [rad] per flight:"]
    for k, v in report["flapping_frequency"].items():
        out.append(f"  {k:<28}{v:8.3f}{report['phase_offsets'].get(k, 0.0):+9.3f}")
    title = ("flapping forces, match with estimation data (Table 8):"
             if report["model"] == "flap" else
             "combined model simulation, match with estimation data:")
    out += ["", metrics_table(flap["metrics"]["estimation"] if report["model"] == "flap"
                              else report["metrics"]["estimation"], title)]
    if "validation" in report["metrics"]:
        out += ["", metrics_table(report["metrics"]["validation"],
                                  "match with validation data (phase aligned):")]
    for name, s in report.get("steady_vs_manoeuvre", {}).items():
        out += ["", f"{name}: steady flight vs manoeuvre (Figures 14 vs 12):",
                f"{'output':<8}{'RMS steady':>12}{'% range':>9}{'non-harm %':>11}"
                f"{'RMS manoeuvre':>15}{'% range':>9}{'non-harm %':>11}"]
        for o in s["steady"]:
            a, b = s["steady"][o], s["manoeuvre"][o]
            out.append(f"{o:<8}{a['rms']:>12.3e}{a['rms_pct']:>9.2f}{a['nonharmonic_pct']:>11.2f}"
                       f"{b['rms']:>15.3e}{b['rms_pct']:>9.2f}{b['nonharmonic_pct']:>11.2f}")
    out += ["", "first flapping peaks, measured/model:"] + _peak_summary(report["peaks"])
    return "\n".join(out + warnings_lines(report))
