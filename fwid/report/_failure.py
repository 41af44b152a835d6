"""Why a report's fits failed, in one clause: for the one line `fwid identify` ends with when
no fit converged."""

from __future__ import annotations

import math

from .._advice import advice
from ._numbers import compact


def _blocks(report: dict) -> list[dict]:
    """The fit blocks behind a report: each flight's, or the one (joint) fit's; for the
    combined model those of its cycle-averaged part."""
    if report.get("model") == "combined":
        return _blocks(report.get("cycle_averaged", {}))
    if "per_flight" in report:
        return [p for p in report["per_flight"] if "fit" in p]
    return [report] if "fit" in report else []


def _finite(x) -> bool:
    return x is not None and math.isfinite(float(x))


def failure_reason(report: dict) -> str:
    """Why the fits of `report` failed, most telling first: a simulation that is not finite,
    an unstable fitted model that runs away from the data, inputs that follow the states
    (a closed loop), else steps that stalled; each with what to try."""
    blocks = _blocks(report)
    method = report.get("method", "output-error")
    others = " or ".join(advice(m) for m in ("multiple-shooting", "filter-error") if m != method)
    scores = [m.get("r2") for b in blocks for m in b.get("metrics", {}).get("estimation",
                                                                             {}).values()]
    closed = [k for k, c in (report.get("closed_loop") or {}).items() if c.get("closed")]
    loop = (f"; the control follows the states (closed loop: {', '.join(closed)}), where "
            f"output error is biased: try {advice('filter-error')}"
            ) if closed and method == "output-error" else ""
    if any(not _finite(b["fit"].get("cost")) for b in blocks) or any(
            not _finite(s) for s in scores if s is not None):
        return (f"the simulation diverged (not finite); check the units and the trim, or try "
                f"{others}{loop}")
    growth = [(max(e[0] for e in b["eigenvalues"]), b.get("flight", "")) for b in blocks
              if b.get("eigenvalues")]
    lam, where = max(growth, default=(float("-inf"), ""))
    if lam > 0:
        worst = compact(min((s for s in scores if s is not None), default=float("nan")))
        follow = ("which output error cannot follow" if method == "output-error"
                  else f"and the {method} fit did not settle")
        return (f"the fitted model is unstable (eigenvalue {lam:+.3g} 1/s"
                f"{' on ' + where if where else ''}): its simulation runs away from the data "
                f"(R2 down to {worst}), {follow}; try {others}{loop}")
    return ("the Gauss-Newton steps stalled without settling (a flat or ragged likelihood); "
            f"see the warnings{loop}")
