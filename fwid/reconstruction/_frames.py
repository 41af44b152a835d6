"""A take's time base from its frame numbers and frame rate (the Motive export's `Frame`
column and `Export Frame Rate`).

Motive rounds its `Time (Seconds)` column (to the millisecond in some versions: 0.008, 0.016,
0.025 at 120 Hz), so the time base is `Frame / rate`, shifted to start at the take's first
time; the time column is only checked against it. A frame number that is missing is a frame
the export left out: a row of NaN (untracked) is put in its place, bridged by the smoother
like any dropout up to `max_dropout`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._errors import FlightDataError


class FrameTimes(NamedTuple):
    """`t` (s): one time per frame from the first to the last; `rows`: where each data row
    lies on `t`; `missing`: the frames of `t` no row holds; `warnings`."""

    t: np.ndarray
    rows: np.ndarray
    missing: np.ndarray
    warnings: list[str]


def frame_times(frames: np.ndarray, time: np.ndarray, rate: float, path: str, first_line: int,
                max_dropout: float, what: str = "Time (Seconds)") -> FrameTimes:
    """The time base of frame numbers `frames` at `rate` (Hz), checked against the time column
    `time` (s), read from data lines starting at `first_line`.

    Frame numbers that are not whole, or do not increase, and a run of missing frames longer
    than `max_dropout` seconds are a `FlightDataError` naming the lines or the frames; a time
    column that departs from the frames by more than its rounding (1 ms) is a warning.
    """
    bad = np.flatnonzero(~np.isfinite(frames) | (np.abs(frames - np.round(frames)) > 1e-6))
    if bad.size:
        i = int(bad[0])
        if not np.isfinite(frames[i]):
            raise FlightDataError(f"{path}, line {first_line + i}: the Frame cell is empty; "
                                  "every row needs its frame number")
        raise FlightDataError(f"{path}, line {first_line + i}: the frame number "
                              f"{frames[i]:g} is not a whole number; re-export the take")
    frames = np.round(frames).astype(np.int64)
    step = np.diff(frames)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        raise FlightDataError(
            f"{path}, line {first_line + i + 1}: frame {frames[i + 1]} follows frame "
            f"{frames[i]}; the frame numbers must increase (one take per file, rows in order)")
    t0 = float(time[0]) if np.isfinite(time[0]) else frames[0] / rate
    rows = frames - frames[0]
    t = t0 + np.arange(rows[-1] + 1) / rate
    present = np.zeros(len(t), bool)
    present[rows] = True
    missing = np.flatnonzero(~present)
    warnings = []
    for i in np.flatnonzero(step > 1):
        n = int(step[i] - 1)
        if n / rate > max_dropout + 1e-9:
            a, b = frames[i] + 1, frames[i + 1] - 1
            raise FlightDataError(
                f"{path}, line {first_line + i + 1}: frames {a} to {b} (t = {t[rows[i] + 1]:.6g} "
                f"to {t[rows[i + 1] - 1]:.6g} s, {n / rate:.3g} s) are missing from the export, "
                f"longer than the {max_dropout:g} s that are bridged; raise --max-dropout, or cut "
                "the take at the gap (export the stretches on either side as takes of their own)")
    if missing.size:
        warnings.append(f"{missing.size} frames missing from the export (first frame "
                        f"{frames[0] + missing[0]}, t = {t[missing[0]]:.6g} s): bridged as "
                        "dropouts")
    off = np.abs(time - t[rows])
    off = np.where(np.isfinite(off), off, 0.0)
    if off.max() > 1e-3 + 1e-6:
        i = int(np.argmax(off))
        warnings.append(
            f"the {what} column departs from Frame / {rate:g} Hz by up to {off[i] * 1e3:.3g} ms "
            f"(frame {frames[i]}, line {first_line + i}); the time base is taken from the frame "
            "numbers")
    return FrameTimes(t, rows, missing, warnings)
