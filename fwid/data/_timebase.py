"""A time base made uniform: samples whose time stamps jitter within a fraction of the step
(an autopilot's log stamps its samples by a millisecond tick, a logger's clock runs between
its samples) are resampled onto the uniform grid, linearly between neighbours.

The limits: in a flight file (`uniform_flight`), a step that departs from the median step by
at most `JITTER` of it is jitter, and any other step an error. A raw recording
(`uniform_time`) comes from a logger whose loop may run unevenly: every grid time between
samples less than `GAP` median steps apart is interpolated; one in a longer step falls in
missing samples, bridged as dropouts. A step at or below zero is an error in both.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._errors import FlightDataError
from .._words import count

#: A step within this fraction of the median step is jitter (resampled), and a step within
#: it of a whole number of median steps holds missing samples.
JITTER = 0.25
#: A raw recording's step longer than this many median steps holds missing samples (the
#: grid times inside it are dropouts); shorter steps are interpolated across.
GAP = 1.5
#: A raw recording whose steps are within this fraction of the median one is uniform
#: already (no resampling).
UNIFORM = 0.01
#: A flight file whose steps are within this fraction of the median one (or within the
#: rounding of its printed time stamps, `time_quantum`) is uniform already: its time stamps
#: are replaced by the exact grid, its samples kept as they are.
UNIFORM_RTOL = 1e-3


def time_quantum(t: np.ndarray) -> float:
    """The rounding of the printed time stamps: 10**-k for the fewest decimals k that
    reproduce `t` (0.0 when `t` is not rounded to 12 decimals or fewer)."""
    t = np.asarray(t, dtype=float)
    for k in range(13):
        s = t * 10.0**k
        if np.max(np.abs(s - np.round(s)), initial=0.0) < 1e-3:
            return 10.0**-k
    return 0.0


def uniform_tolerance(t: np.ndarray, dt: float) -> float:
    """How far [s] a flight file's step may depart from the median step `dt` for its time
    stamps to count as uniform: `UNIFORM_RTOL` of the step, or the rounding of the printed
    stamps if larger, at most `JITTER` of the step."""
    return min(max(UNIFORM_RTOL * dt, 1.01 * time_quantum(t)), JITTER * dt)


def _grid(t: np.ndarray, dt: float):
    """The grid from `t[0]` at step `dt` through `t[-1]`, the sample at or before each grid
    time (`left`) and the fraction of the way to the next sample (`frac`)."""
    d = np.diff(t)
    n = int(round((t[-1] - t[0]) / dt)) + 1
    grid = t[0] + dt * np.arange(n)
    left = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, len(t) - 2)
    frac = np.clip((grid - t[left]) / d[left], 0.0, 1.0)
    return grid, left, frac


def uniform_time(t: np.ndarray, path: str, first_line: int, what: str = "time"):
    """The uniform grid of a raw recording's time stamps `t` and how to get the samples onto
    it.

    **Returns:** `(grid, weights, warnings)`: `grid` (s) from `t[0]` at the median step;
    `weights` `(len(grid), len(t))` as a sparse pair `(left, frac)` of the sample before
    each grid time and the fraction of the way to the next one (`frac` NaN where the grid
    time falls in missing samples), or None when `t` is uniform already; one warning per
    change made. A time stamp that is empty or not increasing is a `FlightDataError` naming
    the line.
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
    grid, left, frac = _grid(t, dt)
    long = d > GAP * dt  # missing samples: only the grid times on a sample are kept
    frac = np.where(long[left], np.where(frac < 1e-9, 0.0, np.where(frac > 1 - 1e-9, 1.0,
                                                                    np.nan)), frac)
    notes = []
    jitter = float(np.max(np.abs(d[~long] / dt - 1))) if np.any(~long) else 0.0
    if jitter > UNIFORM:
        notes.append(_jitter_note(jitter, dt))
    missing = int(np.sum(np.isnan(frac)))
    if missing:
        notes.append(f"{count(missing, 'sample')} missing from the time stamps (steps over "
                     f"{GAP:g} times the typical {dt * 1e3:.4g} ms); bridged as dropouts")
    return grid, (left, frac), notes


def _jitter_note(jitter: float, dt: float) -> str:
    return (f"the time stamps jitter by up to {100 * jitter:.2g}% of the step ({dt * 1e3:.4g} ms); "
            f"resampled onto a uniform {1 / dt:.6g} Hz grid")


def onto_grid(x: np.ndarray, how) -> np.ndarray:
    """Samples `x` (time first) on the grid of `uniform_time` (`how`: its `(left, frac)`):
    linear between neighbours, NaN in missing samples."""
    if how is None:
        return x
    left, frac = how
    x = np.asarray(x, dtype=float)
    f = frac.reshape((-1,) + (1,) * (x.ndim - 1))
    return (1 - f) * x[left] + f * x[left + 1]


def uniform_flight(
    name: str, t: np.ndarray, columns: Mapping[str, np.ndarray]
) -> tuple[np.ndarray, dict[str, np.ndarray], str | None]:
    """A checked flight file's samples on the exact uniform grid (its steps are all within
    `JITTER` of the median step, as `fwid.data._checks.check_time` ensures).

    Steps within `uniform_tolerance` of the median step: the time stamps are replaced
    by the grid through the first and last ones, the samples kept. Steps that jitter
    further (up to `JITTER` of the step): every column is resampled onto the grid from
    `t[0]` at the median step, linearly between neighbours, with a note saying so.

    **Returns:** `(t, columns, note)`; `note` is None when nothing was resampled.
    """
    t = np.asarray(t, dtype=float)
    n = t.shape[0]
    d = np.diff(t)
    dt = float(np.median(d))
    if np.all(np.abs(d - dt) <= uniform_tolerance(t, dt)):
        return t[0] + np.arange(n) * ((t[-1] - t[0]) / (n - 1)), dict(columns), None
    grid, left, frac = _grid(t, dt)
    jitter = float(np.max(np.abs(d / dt - 1)))
    cols = {c: onto_grid(x, (left, frac)) for c, x in columns.items()}
    note = (f"{name}: {_jitter_note(jitter, dt)} (steps within {JITTER:.0%} of the typical "
            "step are resampled; see the guide's page on flight files, docs/guide/data.md)")
    return grid, cols, note
