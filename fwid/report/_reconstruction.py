"""The figure of a reconstructed take: recorded against smoothed position and attitude, the
gyro against the smoothed rates, dropouts shaded, the clock offset in the title.

Each series is drawn through its envelope (`envelope`: the smallest and the largest sample
of each of `POINTS` slices of the take, in time order), which at the figure's width looks as
the whole series does (every glitch and every flapping peak stays) at a fraction of the
drawing time of a minute's 12000 samples per panel; the panels are placed by a fixed layout,
with few ticks, and only the bottom row draws its time axis.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

#: Slices of a take whose extreme samples are drawn (about two per pixel of a panel).
POINTS = 600
#: Tick intervals per axis, at most.
TICKS = 4


def envelope(t: np.ndarray, y: np.ndarray, points: int = POINTS) -> tuple[np.ndarray, np.ndarray]:
    """The smallest and the largest finite sample of each of `points` slices of `y` (in time
    order, at their own times): the series as a figure `points` pixels wide shows it.

    **Arguments:**
    - `t`, `y` `(N,)`: times and samples (NaN: left out);
    - `points`: the slices.

    **Returns:** `(t, y)` of the kept samples, `(N,)` unchanged when `N <= 2 points`.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    ok = np.isfinite(y)
    t, y = t[ok], y[ok]
    n = len(y)
    if n <= 2 * points:
        return t, y
    edges = np.linspace(0, n, points + 1).astype(int)
    lo = np.minimum.reduceat(y, edges[:-1])
    hi = np.maximum.reduceat(y, edges[:-1])
    seg = np.repeat(np.arange(points), np.diff(edges))
    i_lo = np.flatnonzero(y == lo[seg])
    i_hi = np.flatnonzero(y == hi[seg])
    # the first minimum and the first maximum of each slice
    first_lo = i_lo[np.unique(seg[i_lo], return_index=True)[1]]
    first_hi = i_hi[np.unique(seg[i_hi], return_index=True)[1]]
    keep = np.unique(np.concatenate([first_lo, first_hi]))
    return t[keep], y[keep]


def _series(flight):
    """The nine panels' `(name, recorded or None, smoothed, unit)`, in column order."""
    from fwid.reconstruction._rotations import euler_321, quat_to_matrix

    c, raw, e = flight.columns, flight.raw, flight.entry
    ok = raw["tracked"]
    q = np.where(ok[:, None], raw["quat"], [1.0, 0, 0, 0])
    eul_raw = euler_321(quat_to_matrix(q))
    # the recorded psi on the smoothed branch (unwrap both the same way)
    eul_raw[:, 2] += 2 * np.pi * np.round((c["psi"] - eul_raw[:, 2]) / (2 * np.pi))
    eul_raw[~ok] = np.nan
    pos = np.where(ok[:, None], raw["pos"], np.nan)
    cols = [[("x", pos[:, 0], c["x"], "m"), ("y", pos[:, 1], c["y"], "m"),
             ("z", pos[:, 2], c["z"], "m")],
            [(k, np.rad2deg(eul_raw[:, i]), np.rad2deg(c[k]), "deg")
             for i, k in enumerate(("phi", "theta", "psi"))]]
    bias = e.get("gyro_bias_rad_s") or [0.0, 0.0, 0.0]
    gyro = raw.get("gyro")
    cols.append([(k, None if gyro is None else np.rad2deg(gyro[:, i] - bias[i]),
                  np.rad2deg(c[k]), "deg/s") for i, k in enumerate("pqr")])
    return cols


def _title(e) -> str:
    clock = e.get("clock")
    if clock is None:
        cl = "clock offset 0 s (one file)"
    else:
        cl = (f"clock offset {clock['offset_s']:.4f} s ({'given' if clock['given'] else 'found'}"
              f", +-{1e3 * clock['std_s']:.2g} ms, corr {clock['corr']:.3f})")
    return f"{e['flight']}: {cl}; {len(e['dropouts'])} dropouts (shaded)"


def _bands(a, dropouts):
    """The dropouts as one collection of red bands (not an artist per gap)."""
    return a.add_collection(PolyCollection(
        [[(g0, 0), (g0, 1), (g1, 1), (g1, 0)] for g0, g1 in dropouts],
        transform=a.get_xaxis_transform(), facecolor="C3", alpha=0.35, lw=0), autolim=False)


def plot_reconstruction(flight, *, path: str | Path | None = None,
                        figure: Figure | None = None) -> Figure:
    """Draw one reconstructed take: recorded against smoothed position, attitude and rates.

    Three columns (position, Euler angles, body rates), recorded (dots) against smoothed
    (line); the gyro (less its bias) against the smoothed rates; red bands where the body was
    lost; the clock offset and its quality in the title.

    **Arguments:**
    - `flight`: a reconstructed flight;
    - `path`: where to save the figure (PNG), if given;
    - `figure`: a figure this function returned for an earlier take of the same kind (with
      or without a gyro), redrawn with this take's data instead of building a new one (for
      many takes in a row: about half the time); None: a new figure.

    **Returns:** the `matplotlib.figure.Figure`.
    """
    t, e = flight.columns["t"], flight.entry
    cols = _series(flight)
    has_rec = [[rec is not None for _, rec, _, _ in col] for col in cols]
    art = getattr(figure, "_fwid_reconstruction", None)
    if art is None or art["has_rec"] != has_rec:
        figure = Figure(figsize=(13, 8))
        figure.subplots_adjust(left=0.06, right=0.99, bottom=0.07, top=0.94, wspace=0.22,
                               hspace=0.1)
        ax = figure.subplots(3, 3, sharex=True)
        art = {"has_rec": has_rec, "ax": ax, "lines": {}, "bands": {}}
        for col in range(3):
            for r in range(3):
                name, rec, _, unit = cols[col][r]
                a = ax[r, col]
                if rec is not None:
                    label = "gyro - bias" if col == 2 else "recorded"
                    art["lines"][r, col, 0] = a.plot([], [], ".", ms=1.5, color="0.55",
                                                     label=label)[0]
                art["lines"][r, col, 1] = a.plot([], [], lw=1.0, color="C0", label="smoothed")[0]
                a.set_ylabel(f"{name} [{unit}]")
                if r == 0:
                    a.legend(loc="upper right", fontsize=7)
                # few ticks: the axes' text is most of the drawing time
                a.yaxis.set_major_locator(MaxNLocator(nbins=TICKS))
                a.xaxis.set_major_locator(MaxNLocator(nbins=TICKS))
                if r < 2:
                    a.xaxis.set_visible(False)  # the bottom row's time axis serves the column
            ax[2, col].set_xlabel("t [s]")
        figure._fwid_reconstruction = art
    ax = art["ax"]
    for col in range(3):
        for r in range(3):
            _, rec, sm, _ = cols[col][r]
            a = ax[r, col]
            if rec is not None:
                art["lines"][r, col, 0].set_data(*envelope(t, rec))
            art["lines"][r, col, 1].set_data(*envelope(t, sm))
            old = art["bands"].pop((r, col), None)
            if old is not None:
                old.remove()
            if e["dropouts"]:
                art["bands"][r, col] = _bands(a, e["dropouts"])
            a.relim()
            a.autoscale_view()
    figure.suptitle(_title(e))
    if path is not None:
        figure.savefig(path, dpi=100, pil_kwargs={"compress_level": 1})
    return figure
