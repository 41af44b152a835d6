"""Why a report's fits failed, in one clause: for the one line `fwid identify` ends with when
no fit converged."""

from __future__ import annotations

import math

from .._advice import advise
from ._bounded import DIVERGED_RANGES
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


def _diverged(blocks: list[dict]) -> tuple[float, str, str] | None:
    """`(t, signal, flight)` of the earliest simulation that diverged (the metrics'
    `diverged_at_s`, `fwid.report._bounded`), `None` when none did."""
    found = [(m["diverged_at_s"], k, m.get("diverged_in") or b.get("flight", ""))
             for b in blocks for k, m in b.get("metrics", {}).get("estimation", {}).items()
             if m.get("diverged_at_s") is not None]
    return min(found, default=None)


def failure_reason(report: dict) -> str:
    """Why the fits of `report` failed, most telling first: a simulation that is not finite
    or diverged, an unstable fitted model that runs away from the data, else steps that
    stalled; each with the one next step (`fwid._advice.NEXT` for the method in use; for
    output error on flights whose inputs follow the states, the closed loop's)."""
    blocks = _blocks(report)
    method = report.get("method", "output-error")
    scores = [m.get("r2") for b in blocks for m in b.get("metrics", {}).get("estimation",
                                                                             {}).values()]
    closed = [k for k, c in (report.get("closed_loop") or {}).items() if c.get("closed")]
    loop = (f"; the control follows the states (closed loop: {', '.join(closed)}), where "
            "output error is biased") if closed and method == "output-error" else ""

    def step(failure):
        return f"; next: {advise('closed-loop' if loop else failure, method)}"

    if any(not _finite(b["fit"].get("cost")) for b in blocks) or any(
            not _finite(s) for s in scores if s is not None):
        return (f"the simulation diverged (not finite; check the units and the trim){loop}"
                f"{step('diverged')}")
    away = _diverged(blocks)
    growth = [(max(e[0] for e in b["eigenvalues"]), b.get("flight", "")) for b in blocks
              if b.get("eigenvalues")]
    lam, where = max(growth, default=(float("-inf"), ""))
    follow = ("which output error cannot follow" if method == "output-error"
              else f"and the {method} fit did not settle")
    if away is not None:
        t, signal, flight = away
        why = f"the fitted model is unstable (eigenvalue {lam:+.3g} 1/s): " if lam > 0 else ""
        return (f"{why}its simulation diverged from the data at t = {t:.3g} s"
                f"{' on ' + flight if flight else ''} ({signal} beyond "
                f"{DIVERGED_RANGES:.0f} times its measured range), {follow}{loop}"
                f"{step('unstable' if lam > 0 else 'diverged')}")
    if lam > 0:
        worst = compact(min((s for s in scores if s is not None), default=float("nan")))
        return (f"the fitted model is unstable (eigenvalue {lam:+.3g} 1/s"
                f"{' on ' + where if where else ''}): its simulation runs away from the data "
                f"(R2 down to {worst}), {follow}{loop}{step('unstable')}")
    return ("the Gauss-Newton steps stalled without settling (a flat or ragged likelihood)"
            f"{loop}{step('not-converged')}")
