"""Figures in the paper's style: measured vs model (Figs. 6, 7, 9, 10), poles (Figs. 8, 11).

Object-oriented matplotlib only (no pyplot state), so figures can be made from threads,
notebooks and the command line alike.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

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
    """States and forces, measured vs model, with the scaled input (Figures 6, 7, 9, 10)."""
    names = list(flight_fit.measured)
    forces = list(flight_fit.forces_measured)
    ncol = 2 if forces else 1
    nrow = max(len(names), len(forces))
    fig = Figure(figsize=(6 * ncol, 1.9 * nrow + 0.6), layout="constrained")
    axes = fig.subplots(nrow, ncol, squeeze=False, sharex=True)
    t = flight_fit.t
    u_name, u = next(iter(flight_fit.inputs.items()))
    for col, (group, meas, sim, label) in enumerate(
        [(names, flight_fit.measured, flight_fit.simulated, "Measured"),
         (forces, flight_fit.forces_measured, flight_fit.forces_simulated, "Reconstructed")][:ncol]
    ):
        for row in range(nrow):
            ax = axes[row, col]
            if row >= len(group):
                ax.set_visible(False)
                continue
            k = group[row]
            zm, ys = _display(k, meas[k]), _display(k, sim[k])
            ax.plot(t, zm, color="0.2", lw=1.0, label=label)
            ax.plot(t, ys, color="C3", lw=1.2, ls="--", label="Model")
            ax.plot(t, _scaled_input(u, zm), color="C0", lw=0.8, alpha=0.6,
                    label=f"Scaled {u_name} input")
            unit = "deg/s" if k in ("q", "p", "r") else _UNITS.get(k, "")
            ax.set_ylabel(f"d{k} [{unit}]" if unit else f"d{k}")
            m = flight_fit.metrics.get(k)
            if m:
                ax.text(0.99, 0.95, f"corr {m['corr']:.2f}  R2 {m['r2']:.2f}", ha="right",
                        va="top", transform=ax.transAxes, fontsize=7)
        axes[0, col].legend(fontsize=7, loc="upper left", ncol=3)
        axes[-1, col].set_xlabel("t [s]")
    fig.suptitle(title or flight_fit.name)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_poles(eigs: Sequence[np.ndarray], labels: Sequence[str] | None = None, *,
               path: str | Path | None = None, title: str = "") -> Figure:
    """Eigenvalues of several models in one s-plane, with lines of constant damping
    (Figures 8 and 11)."""
    fig = Figure(figsize=(6, 5), layout="constrained")
    ax = fig.subplots()
    allev = np.concatenate([np.asarray(e) for e in eigs]) if len(eigs) else np.zeros(1)
    r = 1.1 * max(1.0, np.max(np.abs(allev)))
    for zeta in (0.16, 0.34, 0.5, 0.64, 0.76, 0.86, 0.94, 0.985):
        ang = np.arccos(zeta)
        for s in (1, -1):
            ax.plot([0, -r * np.cos(ang)], [0, s * r * np.sin(ang)], color="0.85", lw=0.6)
        ax.text(-r * np.cos(ang), r * np.sin(ang), f"{zeta}", fontsize=6, color="0.5")
    for i, e in enumerate(eigs):
        e = np.asarray(e)
        lab = labels[i] if labels is not None else f"data #{i + 1}"
        ax.plot(e.real, e.imag, "x", ms=7, mew=1.5, label=lab)
    ax.axhline(0, color="0.6", lw=0.6)
    ax.axvline(0, color="0.6", lw=0.6)
    ax.set_xlabel("Real axis [1/s]")
    ax.set_ylabel("Imaginary axis [rad/s]")
    ax.legend(fontsize=7)
    ax.set_title(title)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig
