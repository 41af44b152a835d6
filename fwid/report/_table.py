"""Terminal tables in the paper's layouts (Tables 1-6)."""

from __future__ import annotations

import numpy as np


def _chunks(seq, n):
    k = int(np.ceil(len(seq) / n))
    return [seq[i * k:(i + 1) * k] for i in range(n)]


def parameter_table(params: dict, *, columns: int = 3) -> str:
    """Table 1's layout: `param  value  |sigma|  100|sigma/value|`, in `columns` groups."""
    names = list(params)
    groups = _chunks(names, columns)
    head = "  ".join(f"{'param':<8}{'value':>11}{'|sigma|':>10}{'100|s/v|':>9}" for _ in groups)
    lines = [head, "-" * len(head)]
    for r in range(max(len(g) for g in groups)):
        cells = []
        for g in groups:
            if r < len(g):
                k = g[r]
                p = params[k]
                std = p.get("std")
                rel = 100 * abs(std / p["value"]) if std is not None and p["value"] else float("nan")
                cells.append(f"{k:<8}{p['value']:>11.3e}{(std or float('nan')):>10.2e}{rel:>9.2f}")
            else:
                cells.append(" " * 38)
        lines.append("  ".join(cells).rstrip())
    return "\n".join(lines)


def metrics_table(metrics: dict, title: str = "") -> str:
    """Table 2's layout: output correlation, R^2, RMS and RMS as % of range, per output."""
    lines = [title] if title else []
    lines.append(f"{'output':<8}{'corr':>7}{'R2':>8}{'RMS':>11}{'RMS %':>8}")
    for k, m in metrics.items():
        lines.append(f"{k:<8}{m['corr']:>7.2f}{m['r2']:>8.2f}{m['rms']:>11.3e}{m['rms_pct']:>8.2f}")
    return "\n".join(lines)


def modes_table(modes: list[dict]) -> str:
    """Eigenvalues (Tables 3, 6) with each mode's frequency, damping or time constant."""
    lines = [f"{'eigenvalue':<24}{'mode':<12}{'wn [rad/s]':>11}{'zeta':>7}{'tau [s]':>9}"]
    for m in modes:
        re, im = m["eigenvalue"]
        ev = f"{re:.4f} +/- {im:.4f}i" if im else f"{re:.4f}"
        if m["kind"] == "oscillatory":
            lines.append(f"{ev:<24}{'oscillatory':<12}{m['wn']:>11.3f}{m['zeta']:>7.3f}{'':>9}")
        else:
            lines.append(f"{ev:<24}{'aperiodic':<12}{'':>11}{'':>7}{m['tau']:>9.3f}")
    return "\n".join(lines)


def identification_summary(report: dict) -> str:
    """The terminal summary of `fwid identify`: parameters, modes, metrics."""
    out = [f"fwid identify: model {report['model']}, flights: {', '.join(report['flights'])}"]
    if "summary" in report:
        out.append(f"({report['summary']})")
    out += ["", parameter_table(report["parameters"]), "", modes_table(report["modes"]), ""]
    out.append(metrics_table(report["metrics"]["estimation"], "match with estimation data:"))
    if "validation" in report["metrics"]:
        out += ["", metrics_table(report["metrics"]["validation"], "match with validation data:")]
    return "\n".join(out)
