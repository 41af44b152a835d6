"""The figure of a reconstructed take: recorded against smoothed position and attitude, the
gyro against the smoothed rates, dropouts shaded, the clock offset in the title."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure


def plot_reconstruction(flight, *, path: str | Path | None = None) -> Figure:
    """Draw one reconstructed take: recorded against smoothed position, attitude and rates.

    Three columns (position, Euler angles, body rates), recorded (dots) against smoothed
    (line); the gyro (less its bias) against the smoothed rates; red bands where the body was
    lost; the clock offset and its quality in the title.

    **Arguments:**
    - `flight`: a reconstructed flight;
    - `path`: where to save the figure (PNG), if given.

    **Returns:** the `matplotlib.figure.Figure`.
    """
    from fwid.reconstruction._rotations import euler_321, quat_to_matrix

    c, raw, e = flight.columns, flight.raw, flight.entry
    t = c["t"]
    ok = raw["tracked"]
    q = np.where(ok[:, None], raw["quat"], [1.0, 0, 0, 0])
    eul_raw = euler_321(quat_to_matrix(q))
    # the recorded psi on the smoothed branch (unwrap both the same way)
    eul_raw[:, 2] += 2 * np.pi * np.round((c["psi"] - eul_raw[:, 2]) / (2 * np.pi))
    fig = Figure(figsize=(13, 8), layout="constrained")
    ax = fig.subplots(3, 3, sharex=True)
    rows = [
        [("x", raw["pos"][:, 0], c["x"], "m"), ("y", raw["pos"][:, 1], c["y"], "m"),
         ("z", raw["pos"][:, 2], c["z"], "m")],
        [(k, np.rad2deg(eul_raw[:, i]), np.rad2deg(c[k]), "deg")
         for i, k in enumerate(("phi", "theta", "psi"))],
    ]
    bias = e.get("gyro_bias_rad_s") or [0.0, 0.0, 0.0]
    gyro = raw.get("gyro")
    rows.append([(k, None if gyro is None else np.rad2deg(gyro[:, i] - bias[i]),
                  np.rad2deg(c[k]), "deg/s") for i, k in enumerate("pqr")])
    for col in range(3):
        for r in range(3):
            name, rec, sm, unit = rows[col][r]
            a = ax[r, col]
            if rec is not None:
                label = "gyro - bias" if col == 2 else "recorded"
                a.plot(t[ok] if col < 2 else t, rec[ok] if col < 2 else rec, ".", ms=1.5,
                       color="0.55", label=label)
            a.plot(t, sm, lw=1.0, color="C0", label="smoothed")
            for g0, g1 in e["dropouts"]:
                a.axvspan(g0, g1, color="C3", alpha=0.35, lw=0)
            a.set_ylabel(f"{name} [{unit}]")
            if r == 0:
                a.legend(loc="upper right", fontsize=7)
        ax[2, col].set_xlabel("t [s]")
    clock = e.get("clock")
    if clock is None:
        cl = "clock offset 0 s (one file)"
    else:
        cl = (f"clock offset {clock['offset_s']:.4f} s ({'given' if clock['given'] else 'found'}"
              f", +-{1e3 * clock['std_s']:.2g} ms, corr {clock['corr']:.3f})")
    fig.suptitle(f"{e['flight']}: {cl}; {len(e['dropouts'])} dropouts (shaded)")
    if path is not None:
        fig.savefig(path, dpi=100)
    return fig
