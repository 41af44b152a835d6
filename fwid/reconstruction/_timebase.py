"""A recording's time base made uniform: samples whose time stamps jitter within a fraction
of the step (an autopilot's log stamps its samples by a millisecond tick, a logger's clock
runs between its samples) are resampled onto the uniform grid, missing samples become
dropouts, and anything else is refused in one line.

The limits: a step that departs from the median step by at most `JITTER` of it is jitter;
one that is close to a whole number of steps (within `JITTER`) holds missing samples; a
step of another length, or one at or below zero, is an error naming the line.
"""

from __future__ import annotations

import numpy as np

from .._errors import FlightDataError

#: A step within this fraction of the median step is jitter (resampled), and a step within
#: it of a whole number of median steps holds missing samples.
JITTER = 0.25
#: Steps within this fraction of the median one are uniform already (no resampling).
UNIFORM = 0.01


def uniform_time(t: np.ndarray, path: str, first_line: int, what: str = "time"):
    """The uniform grid of the time stamps `t` and how to get the samples onto it.

    **Returns:** `(grid, weights, warnings)`: `grid` (s) from `t[0]` at the median step;
    `weights` `(len(grid), len(t))` as a sparse pair `(left, frac)` of the sample before
    each grid time and the fraction of the way to the next one (`frac` NaN where the grid
    time falls in missing samples), or None when `t` is uniform already; one warning per
    change made. A time stamp that is empty, not increasing, or a step that is neither
    jitter nor missing samples is a `FlightDataError` naming the line.
    """
    if len(t) < 3:
        raise FlightDataError(f"{path}: only {len(t)} samples; a recording needs at least 3")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise FlightDataError(f"{path}, line {first_line + int(bad[0])}: the {what} cell is "
                              "empty; every row needs its time")
    d = np.diff(t)
    dt = float(np.median(d))
    if dt <= 0 or np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) if np.any(d <= 0) else 0
        raise FlightDataError(
            f"{path}, line {first_line + i + 1}: the {what} does not increase ({t[i]:.6g} then "
            f"{t[i + 1]:.6g}); sort the rows by time and drop repeated samples")
    if np.all(np.abs(d - dt) <= UNIFORM * dt):
        return t, None, []
    k = np.round(d / dt)
    off = np.abs(d / dt - k)
    bad = np.flatnonzero((k < 1) | (off > JITTER))
    if bad.size:
        i = int(bad[0])
        raise FlightDataError(
            f"{path}, line {first_line + i + 1}: a step of {d[i]:.6g} s at {what} {t[i + 1]:.6g} "
            f"is neither the take's step {dt:.6g} s (within {JITTER:.0%}) nor a whole number of "
            "them (missing samples); export the samples at a uniform rate")
    n = int(round((t[-1] - t[0]) / dt)) + 1
    grid = t[0] + dt * np.arange(n)
    left = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, len(t) - 2)
    frac = np.clip((grid - t[left]) / d[left], 0.0, 1.0)
    frac = np.where(k[left] > 1, np.where(frac < 1e-9, 0.0, np.where(frac > 1 - 1e-9, 1.0,
                                                                        np.nan)), frac)
    notes = []
    jitter = float(np.max(np.abs(d[k == 1] / dt - 1))) if np.any(k == 1) else 0.0
    if jitter > UNIFORM:
        notes.append(f"the time stamps jitter by up to {jitter:.0%} of the step "
                     f"({dt * 1e3:.4g} ms); resampled onto a uniform {1 / dt:.6g} Hz grid")
    missing = int(np.sum(k[k > 1] - 1))
    if missing:
        notes.append(f"{missing} sample{'s' if missing != 1 else ''} missing from the time "
                     "stamps; bridged as dropouts")
    return grid, (left, frac), notes


def onto_grid(x: np.ndarray, how) -> np.ndarray:
    """Samples `x` (time first) on the grid of `uniform_time` (`how`: its `(left, frac)`):
    linear between neighbours, NaN in missing samples."""
    if how is None:
        return x
    left, frac = how
    x = np.asarray(x, dtype=float)
    f = frac.reshape((-1,) + (1,) * (x.ndim - 1))
    return (1 - f) * x[left] + f * x[left + 1]
