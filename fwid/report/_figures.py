"""Figures in the paper's style: measured vs model (Figs. 6, 7, 9, 10), poles (Figs. 8, 11).

Object-oriented matplotlib only (no pyplot state), so figures can be made from threads,
notebooks and the command line alike.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from ._bounded import clip_to_measured, drawable
from ._numbers import compact

_DEG = {"q", "p", "r", "theta", "phi", "psi", "alpha", "de", "dr"}
_UNITS = {"q": "deg/s", "p": "deg/s", "r": "deg/s", "theta": "deg", "phi": "deg",
          "u": "m/s", "w": "m/s", "v": "m/s", "X": "N", "Y": "N", "Z": "N",
          "L": "N m", "M": "N m", "N": "N m"}


def _display(name, x):
    return np.rad2deg(x) if name in _DEG else x


def _scaled_input(u, target):
    """The input rescaled onto a panel's range (the paper's 'scaled elev. input')."""
    lo, hi = np.nanmin(target), np.nanmax(target)
    span = np.ptp(u)
    if span == 0:
        return np.full_like(u, (lo + hi) / 2)
    return lo + (u - np.min(u)) / span * (hi - lo)


def plot_flight_fit(flight_fit, *, path: str | Path | None = None, title: str = "") -> Figure:
    """States and forces of one flight, measured against the model (Figures 6, 7, 9, 10).

    The scaled input is drawn with every signal, and under each signal its residual
    (measured - model), where the model misses. States are perturbations from the trim,
    angles and rates in degrees for reading (the reports and tables are in radians); forces
    and moments in N and N m. A simulation that diverged (`fwid.report._bounded`) is drawn
    within the measured range, its axis kept there, and marked where it diverged.

    **Arguments:**

    - `flight_fit`: a [`fwid.FlightFit`][] (e.g. `Identification.validation[0]`).
    - `path`: where to save the figure (PNG); not saved when `None`.
    - `title`: the figure's title.

    **Returns:** the `matplotlib.figure.Figure`.
    """
    names = list(flight_fit.measured)
    forces = list(flight_fit.forces_measured)
    ncol = 2 if forces else 1
    nrow = max(len(names), len(forces))
    fig = Figure(figsize=(6 * ncol, 2.4 * nrow + 0.9), layout="constrained")
    axes = fig.subplots(2 * nrow, ncol, squeeze=False, sharex=True,
                        gridspec_kw=dict(height_ratios=[3, 1] * nrow))
    t = flight_fit.t
    u_name, u = next(iter(flight_fit.inputs.items()))
    u_disp = _display(u_name, np.asarray(u))
    u_unit = "deg" if u_name in _DEG else ""
    u_label = f"{u_name} input, scaled (range {np.ptp(u_disp):.3g} {u_unit})".replace(" )", ")")
    for col, (group, meas, sim, label) in enumerate(
        [(names, flight_fit.measured, flight_fit.simulated, "Measured"),
         (forces, flight_fit.forces_measured, flight_fit.forces_simulated, "Reconstructed")][:ncol]
    ):
        last = None
        for row in range(nrow):
            ax, res = axes[2 * row, col], axes[2 * row + 1, col]
            if row >= len(group):
                ax.set_visible(False)
                res.set_visible(False)
                continue
            k = group[row]
            zm, ys = _display(k, meas[k]), _display(k, sim[k])
            ax.plot(t, zm, color="0.2", lw=1.0, label=label)
            ax.plot(t, drawable(t, zm, ys), color="C3", lw=1.2, ls="--", label="Model")
            ax.plot(t, _scaled_input(u_disp, zm), color="C0", lw=0.8, alpha=0.6, label=u_label)
            unit = _UNITS.get(k, "")
            ax.set_ylabel(f"\u0394{k} [{unit}]" if unit else f"\u0394{k}")
            res.plot(t, zm - drawable(t, zm, ys), color="C3", lw=0.8)
            res.axhline(0, color="0.6", lw=0.5)
            res.set_ylabel("resid.", fontsize=7)
            clip_to_measured(ax, t, zm, ys, residual_ax=res)
            m = flight_fit.metrics.get(k)
            if m:
                ax.text(0.99, 0.95, f"corr {compact(m['corr'])}  R2 {compact(m['r2'])}", ha="right",
                        va="top", transform=ax.transAxes, fontsize=7)
            last = res
        if last is not None:  # time ticks on every column's last visible panel
            last.xaxis.set_tick_params(labelbottom=True)
            last.set_xlabel("t [s]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if ncol == 2:
        h2, l2 = axes[0, 1].get_legend_handles_labels()
        handles, labels = handles + h2[:1], labels + l2[:1]
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=7)
    fig.suptitle((title or flight_fit.name) + "\nstates: perturbations from the trim "
                 "(degrees for angles and rates)", fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


_MARKERS = ("x", "+", "o", "s", "^", "v", "D", "*")


def plot_poles(eigs: Sequence[np.ndarray], labels: Sequence[str] | None = None, *,
               path: str | Path | None = None, title: str = "",
               highlight: int | None = None) -> Figure:
    """Eigenvalues of several models in one s-plane (Figures 8 and 11).

    Labelled rays of constant damping ratio and circles of constant natural frequency; every
    model its own colour and marker (legible with 16 flights).

    **Arguments:**

    - `eigs`: one array of eigenvalues per model.
    - `labels`: a label per model (for the legend).
    - `path`: where to save the figure (PNG); not saved when `None`.
    - `title`: the figure's title.
    - `highlight`: the index of a model drawn larger and black (e.g. the joint fit beside
      the individual ones).

    **Returns:** the `matplotlib.figure.Figure`.
    """
    fig = Figure(figsize=(7, 5.2), layout="constrained")
    ax = fig.subplots()
    allev = np.concatenate([np.asarray(e) for e in eigs]) if len(eigs) else np.zeros(1)
    r = 1.1 * max(1.0, float(np.max(np.abs(allev))))
    for zeta in (0.1, 0.2, 0.4, 0.6, 0.8, 0.95):
        ang = np.arccos(zeta)
        for s in (1, -1):
            ax.plot([0, -r * np.cos(ang)], [0, s * r * np.sin(ang)], color="0.85", lw=0.6)
        ax.text(-r * np.cos(ang), r * np.sin(ang), f"\u03b6={zeta}", fontsize=6, color="0.45",
                ha="center", va="bottom")
    ticks = [w for w in np.array([1, 2, 5]) * 10.0 ** np.arange(-1, 4)[:, None] for w in w]
    rings = [w for w in sorted(ticks) if w <= r][-4:]
    phi = np.linspace(np.pi / 2, 3 * np.pi / 2, 100)
    for w in rings:
        ax.plot(w * np.cos(phi), w * np.sin(phi), color="0.88", lw=0.6)
        ax.text(-w, 0, f"\u03c9n={w:g}", fontsize=6, color="0.45", ha="right", va="bottom")
    cmap = matplotlib.colormaps["tab20" if len(eigs) > 10 else "tab10"]
    for i, e in enumerate(eigs):
        e = np.asarray(e)
        lab = labels[i] if labels is not None else f"data #{i + 1}"
        if highlight is not None and i == highlight:
            ax.plot(e.real, e.imag, "X", ms=10, color="k", label=lab, zorder=5)
            continue
        ax.plot(e.real, e.imag, _MARKERS[i % len(_MARKERS)], ms=6, mew=1.3, mfc="none",
                color=cmap(i % cmap.N), label=lab)
    ax.axhline(0, color="0.6", lw=0.6)
    ax.axvline(0, color="0.6", lw=0.6)
    ax.set_xlabel("Real axis [1/s]")
    ax.set_ylabel("Imaginary axis [rad/s]")
    fig.legend(fontsize=6, loc="outside right upper", ncol=1 if len(eigs) <= 20 else 2)
    ax.set_title(title)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig
