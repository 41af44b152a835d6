"""Whether a flight's quiet start is long enough for its trim.

The trim ([`fwid.data.estimate_trim`][]) is the mean of every column over the quiet start,
the steady flight before the first input; it needs at least `QUIET_WINDOW` (0.2 s) of it.
A manoeuvre that starts earlier leaves the trim to samples that hold part of it. The input's
level at the start is judged on its average over one flapping (ripple) period, which removes
the ripple without smearing the input's steps over the whole window; the manoeuvre has begun
where that average leaves its first value, or at the first input, whichever comes first.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ._trim import QUIET_WINDOW, SMOOTH_WINDOW, _box, _Input, _window, trim_window

#: The averaging window [s] of an input without a ripple.
STEADY_WINDOW = 0.05


def quiet_start(t: np.ndarray, x: np.ndarray, first: int | None = None, *,
                n_sigma: float = 5.0, frac: float = 0.1) -> float:
    """How long [s] the control input `x` holds its level at the start of the flight.

    The input averaged over one ripple period (`STEADY_WINDOW` without a ripple) departs
    from its first value once it differs by more than `max(n_sigma * noise, frac * range)`
    (as in [`fwid.data.first_input_index`][]); the quiet start ends there, or at `first`
    (the first input) if earlier. The whole flight when the input never moves.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = t.shape[0]
    end = float(t[-1] - t[0]) if n else 0.0
    if first is not None and 0 <= first < n:
        end = float(t[first] - t[0])
    if n < 3 or not np.all(np.isfinite(x)):
        return end
    a = _Input(t, x, SMOOTH_WINDOW, QUIET_WINDOW)
    if a.peak <= a.tiny:
        return end
    box = _box(a.period if a.period is not None else float(_window(t, STEADY_WINDOW)))
    m = box.shape[0]
    z = np.convolve(x, box, mode="valid")  # z[k]: the average of x[k : k + m]
    stop = z.shape[0] if first is None else max(0, min(z.shape[0], first - m + 1))
    thr = a.threshold(n_sigma, frac, a.sigma_w * float(np.linalg.norm(box)))
    moved = np.flatnonzero(np.abs(z[:stop] - z[0]) > thr)
    if moved.size:
        end = min(end, float(t[min(n - 1, int(moved[0]) + m // 2)] - t[0]))
    return end


def quiet_start_note(name: str, t: np.ndarray, columns: Mapping[str, np.ndarray], col: str,
                     first: int | None, sidecar: str) -> str | None:
    """A warning, one line, when the quiet start of the flight `name` (its input `col`) is
    shorter than the trim needs: how long it was, how long it must be, what the trim was
    taken from and how to give the trim instead (the sidecar `sidecar`). None when it is
    long enough."""
    t = np.asarray(t, dtype=float)
    quiet = quiet_start(t, columns[col], first)
    if quiet >= QUIET_WINDOW * (1 - 1e-9):
        return None
    stop = trim_window(t, first)
    taken = float(t[min(stop, t.shape[0] - 1)] - t[0])
    keys = [c for c in ("u", "w", "theta", "v", "phi") if c in columns][:3] or ["u", "w", "theta"]
    example = ", ".join(f'"{c}0": ..' for c in keys)
    return (
        f"{name}: no quiet start: the input '{col}' moves {quiet:.2g} s in, but the trim needs "
        f"at least {QUIET_WINDOW:g} s ({_window(t, QUIET_WINDOW)} samples) of steady flight "
        f"before the manoeuvre; the trim was taken from the first {taken:.2g} s ({stop} "
        f"samples), which hold part of the manoeuvre; record a steady stretch before the "
        f"input, or give the trim in {sidecar}: {{\"trim\": {{{example}}}}}"
    )
