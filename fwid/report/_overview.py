"""One figure for a batch of flights: every flight's fit in a grid (a row a flight, a column
an output), or, for many flights, the worst and the best few by R2. What `fwid identify`
draws by default instead of one figure per flight (`--figures all` draws those too)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ._figures import _UNITS, _display, _scaled_input
from ._bounded import clip_to_measured, drawable
from ._numbers import compact


def mean_r2(flight_fit) -> float:
    """The mean R2 of a flight fit's outputs (NaN-safe): how the overview ranks flights."""
    r2 = [m["r2"] for k, m in flight_fit.metrics.items() if k in flight_fit.measured]
    r2 = np.asarray(r2, dtype=float)
    return float(np.nanmean(r2)) if np.isfinite(r2).any() else float("nan")


def overview_rows(fits: Sequence, most: int = 8) -> list[tuple[str, object]]:
    """The rows of the overview, `(label, flight_fit)`: all of them when there are at most
    `most`, else the `most // 2` worst and the rest best by [`mean_r2`][] (worst first)."""
    if len(fits) <= most:
        return [("", f) for f in fits]
    order = sorted(range(len(fits)), key=lambda i: np.nan_to_num(mean_r2(fits[i]), nan=-np.inf))
    worst, best = order[: most // 2], order[len(order) - (most - most // 2):]
    return [("worst", fits[i]) for i in worst] + [("best", fits[i]) for i in best]


def plot_fits_overview(fits: Sequence, *, path: str | Path | None = None, title: str = "",
                       most: int = 8, parts: Sequence[str] | None = None) -> Figure:
    """Measured vs model for a batch of flight fits in one grid: a row per flight (all of
    them up to `most`, else the worst and best few by mean R2), a column per output, the
    scaled input behind; each row says the flight, its part (`parts[i]`, e.g. "estimation")
    and its mean R2. States as in [`fwid.plot_flight_fit`][] (perturbations, degrees); a
    simulation that diverged is kept to the measured range and marked where it did."""
    parts = list(parts) if parts is not None else [""] * len(fits)
    part_of = {id(f): p for f, p in zip(fits, parts)}
    rows = overview_rows(list(fits), most)
    names = list(rows[0][1].measured) if rows else []
    fig = Figure(figsize=(2.6 * max(len(names), 1) + 0.6, 1.35 * max(len(rows), 1) + 1.0))
    axes = fig.subplots(max(len(rows), 1), max(len(names), 1), squeeze=False, sharex="row")
    fig.subplots_adjust(left=0.07, right=0.99, top=1 - 0.75 / fig.get_figheight(),
                        bottom=0.45 / fig.get_figheight(), hspace=0.55, wspace=0.3)
    for i, (rank, ff) in enumerate(rows):
        u_name, u = next(iter(ff.inputs.items()))
        u_disp = _display(u_name, np.asarray(u))
        for j, k in enumerate(names):
            ax = axes[i, j]
            zm, ys = _display(k, ff.measured[k]), _display(k, ff.simulated[k])
            ax.plot(ff.t, _scaled_input(u_disp, zm), color="C0", lw=0.6, alpha=0.5)
            ax.plot(ff.t, zm, color="0.2", lw=0.8)
            ax.plot(ff.t, drawable(ff.t, zm, ys), color="C3", lw=0.9, ls="--")
            clip_to_measured(ax, ff.t, zm, ys)
            ax.tick_params(labelsize=6)
            if i == 0:
                unit = _UNITS.get(k, "")
                ax.set_title(f"\u0394{k} [{unit}]" if unit else f"\u0394{k}", fontsize=8)
        label = " ".join(s for s in (rank, part_of.get(id(ff), "")) if s)
        axes[i, 0].set_ylabel(f"{ff.name}\n{label}\nR2 {compact(mean_r2(ff))}".replace("\n\n", "\n"),
                              fontsize=6)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]", fontsize=7)
    shown = "" if len(rows) == len(fits) else f" (the worst and best {len(rows)} of {len(fits)})"
    fig.suptitle(f"{title or 'fits'}{shown}: measured (grey) vs model (red dashed), scaled "
                 "input (blue)", fontsize=9)
    if path is not None:
        fig.savefig(path, dpi=100)
    return fig
