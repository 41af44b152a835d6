"""A time window on a flight: `START:END` seconds on the flight's own `t` column (not from
0), either side open. The rows kept are those with `START <= t <= END`; the flight's trim
and first input are then found on what is kept (its quiet start is the window's)."""

from __future__ import annotations

import math
import re

import numpy as np

from .._errors import FlightDataError, InputError

#: Shortest flight (s) a window may leave: a few periods of the fastest cycle-averaged
#: modes (a few Hz) and the quiet start the trim is estimated from.
MIN_WINDOW = 2.0

_FORM = ("give START:END in seconds on the flights' own t column, e.g. --window 12.5:40 "
         "(START: or :END leaves that side open)")
_NUMBER = r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)?\s*"


def parse_window(text: str) -> tuple[float | None, float | None]:
    """`(start, end)` of `START:END` (None for an open side); an `InputError` naming the
    expected form, with an example, for anything else."""
    m = re.fullmatch(_NUMBER + ":" + _NUMBER, text or "")
    if m is None or (m.group(1) is None and m.group(2) is None):
        raise InputError(f"--window {text}: not START:END; {_FORM}")
    start, end = (None if g is None else float(g) for g in m.groups())
    if any(v is not None and not math.isfinite(v) for v in (start, end)):
        raise InputError(f"--window {text}: not START:END; {_FORM}")
    if start is not None and end is not None and start >= end:
        raise InputError(f"--window {text}: START ({start:g}) is not before END ({end:g}); "
                         f"{_FORM}")
    return start, end


def window_text(window) -> str:
    """`START:END` as given back (an open side empty)."""
    return ":".join("" if v is None else f"{v:g}" for v in window)


def window_rows(where: str, t: np.ndarray, window) -> slice:
    """The rows of `t` inside `window` (`(start, end)`, None: open); a `FlightDataError`
    naming the flight, its time span and the fix when fewer than `MIN_WINDOW` seconds
    are left."""
    start, end = window
    lo = -np.inf if start is None else start
    hi = np.inf if end is None else end
    idx = np.flatnonzero((t >= lo - 1e-9) & (t <= hi + 1e-9))
    kept = 0.0 if idx.size < 2 else float(t[idx[-1]] - t[idx[0]])
    if kept < MIN_WINDOW - 1e-9:
        left = ("none of it" if idx.size == 0 else f"{kept:.3g} s of it")
        raise FlightDataError(
            f"{where}: --window {window_text(window)} leaves {left}, the flight runs from "
            f"t = {t[0]:.6g} to {t[-1]:.6g} s; give a window of at least {MIN_WINDOW:g} s "
            f"inside that span (seconds on the flight's own t, e.g. --window "
            f"{t[0]:.6g}:{min(t[-1], t[0] + max(MIN_WINDOW, 0.5 * (t[-1] - t[0]))):.6g})")
    return slice(int(idx[0]), int(idx[-1]) + 1)
