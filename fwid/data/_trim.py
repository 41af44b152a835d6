"""Where the manoeuvre starts, and the trim (the steady condition before it).

The measured elevator of a flapping-wing vehicle ripples at the flapping frequency
(11-13 Hz for the DelFly), so the control input is low-pass smoothed before looking for
the first departure from its initial level. Everything here is plain numpy: it runs once
per file, at load time.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from jaxtyping import Float

if TYPE_CHECKING:  # jaxtyping's ArrayLike imports JAX, which reading a file needs not
    from jaxtyping import ArrayLike

#: Control-input columns, in the order they are preferred when both vary equally.
INPUT_COLUMNS = ("de", "dr")

#: Length [s] of the moving-average window that smooths the input (applied twice).
SMOOTH_WINDOW = 0.2

#: Length [s] of the initial window that gives the input's initial level and noise, and the
#: shortest quiet start the trim is taken from: when no input is found or it starts earlier
#: than this, the trim is the mean of the first `QUIET_WINDOW` seconds.
QUIET_WINDOW = 0.2


def _window(t: np.ndarray, seconds: float) -> int:
    if t.shape[0] < 2:
        return 1
    dt = float(np.median(np.diff(t)))
    if not np.isfinite(dt) or dt <= 0:
        return 1
    return int(min(t.shape[0], max(1, round(seconds / dt))))


def _box(w: float) -> np.ndarray:
    """A moving-average kernel of (possibly fractional) length `w` samples: `floor(w)` unit
    taps, plus two end taps sharing the fraction; normalised to sum 1."""
    m = max(1, int(np.floor(w)))
    frac = max(0.0, w - m)
    k = np.ones(m) if frac < 1e-6 else np.concatenate([[frac / 2], np.ones(m), [frac / 2]])
    return k / k.sum()


def _moving_average(
    x: np.ndarray, w: float, period: float | None = None, flip: bool = False
) -> np.ndarray:
    """Centred moving average of length `w` samples (fractional allowed), same length as `x`.

    Beyond the ends, `x` is continued by a whole number of ripple periods when `period`
    (in samples) is given, so that the ripple still averages out there; else by the mean
    of its first / last samples (not by the edge sample, at a random ripple phase). An
    even-length kernel is half a sample off centre: `flip` puts it on the other side.
    """
    n = x.shape[0]
    k = _box(min(w, n))
    if k.shape[0] <= 1:
        return x.copy()
    left = k.shape[0] // 2
    right = k.shape[0] - 1 - left
    if flip:
        left, right = right, left
    head = tail = None
    if period is not None:
        shift = int(round(period * np.ceil(max(left, right, 1) / period)))
        if max(left, right) <= shift <= n:
            head = x[shift - left : shift]
            tail = x[n - shift : n - shift + right]
    if head is None:
        m = k.shape[0]
        head = np.full(left, x[:m].mean())
        tail = np.full(right, x[-m:].mean())
    return np.convolve(np.concatenate([head, x, tail]), k, mode="valid")


def _smooth2(x: np.ndarray, w: float, period: float | None = None) -> np.ndarray:
    """The moving average applied twice (a triangular window, centred)."""
    return _moving_average(_moving_average(x, w, period), w, period, flip=True)


def _ripple_period(t: np.ndarray, x: np.ndarray, window: float) -> float | None:
    """The period, in samples, of a dominant ripple above `1.5 / window` Hz (7.5 Hz by
    default), e.g. the flapping ripple of a measured control surface; `None` when there is
    no clear one."""
    n = x.shape[0]
    if n < 32:
        return None
    dt = float(np.median(np.diff(t)))
    r = x - _smooth2(x, _window(t, window))
    spec = np.abs(np.fft.rfft((r - r.mean()) * np.hanning(n))) ** 2
    freq = np.fft.rfftfreq(n, dt)
    band = np.flatnonzero((freq >= 1.5 / window) & (freq <= 0.8 * freq[-1]))
    if band.size < 8:
        return None
    k = int(band[np.argmax(spec[band])])
    # A ripple is a narrow peak, with most of the high-frequency power within 1 Hz of it
    # (the residual of an input's steps, by contrast, spreads over all frequencies).
    near = band[np.abs(freq[band] - freq[k]) <= 1.0]
    if not spec[k] > 20.0 * np.median(spec[band]) or spec[near].sum() < 0.3 * spec[band].sum():
        return None
    # Parabolic interpolation of the log-spectrum for a sub-bin frequency.
    lo, mid, hi = np.log(spec[k - 1 : k + 2] + 1e-300)
    den = lo - 2 * mid + hi
    off = float(np.clip(0.5 * (lo - hi) / den, -0.5, 0.5)) if den < 0 else 0.0
    period = 1.0 / ((k + off) * (freq[1] - freq[0]) * dt)
    return period if 2.0 <= period <= n / 4 else None


def _robust_std(x: np.ndarray) -> float:
    if x.size == 0:
        return 0.0
    return 1.4826 * float(np.median(np.abs(x - np.median(x))))


class _Input:
    """A control input, analysed: ripple period, smoothed signal, initial level, noise."""

    def __init__(self, t, x, window, quiet):
        n = x.shape[0]
        self.n0 = _window(t, quiet)
        self.period = _ripple_period(t, x, window)
        w = float(_window(t, window))
        if self.period is not None:
            # A whole number of ripple periods: the moving average removes the ripple.
            w = self.period * max(1, round(w / self.period))
        self.w = min(w, float(n))
        self.y = _smooth2(x, self.w, self.period)
        self.level = float(self.y[: self.n0].mean())
        self.dev = self.y - self.level
        self.peak = float(np.max(np.abs(self.dev)))
        self.tiny = 1e-12 * (1.0 + float(np.max(np.abs(x))))
        # Noise of the smoothed input: the white-noise level (from second differences of the
        # input averaged over one ripple period: robust to the ripple, and with a median, to
        # the input's steps), times the gain of the smoothing kernel.
        box = _box(self.period) if self.period is not None else np.ones(1)
        d2 = np.diff(np.convolve(x, box, mode="valid"), 2)
        self.sigma_w = _robust_std(d2) / float(np.linalg.norm(np.convolve([1.0, -2.0, 1.0], box)))
        kernel = _box(self.w)
        self.sigma = self.sigma_w * float(np.linalg.norm(np.convolve(kernel, kernel)))

    def threshold(self, n_sigma: float, frac: float, sigma: float | None = None) -> float:
        """A departure from the initial level: more than `n_sigma` times the noise (`sigma`,
        default that of the smoothed input) and more than `frac` of the smoothed range."""
        sigma = self.sigma if sigma is None else sigma
        return max(n_sigma * sigma, frac * float(self.y.max() - self.y.min()), self.tiny)

    def excitation(self) -> float:
        """Largest smoothed excursion from the initial level, in units of its noise."""
        if self.peak <= self.tiny:
            return 0.0
        return self.peak / max(self.sigma, self.tiny)


def _half_crossing(dev, s, start, stop):
    """First index in `start:stop` where `s * dev` reaches half its maximum there."""
    seg = s * dev[start:stop]
    if seg.size == 0 or seg.max() <= 0:
        return None
    crossing = np.flatnonzero(seg >= 0.5 * seg.max())
    return int(start + crossing[0])


def smooth_input(
    t: Float[ArrayLike, " n"], x: Float[ArrayLike, " n"], window: float = SMOOTH_WINDOW
) -> Float[np.ndarray, " n"]:
    """The control input, low-pass smoothed: a moving average of about `window` seconds,
    applied twice. When the input ripples (a dominant frequency above `1.5 / window`, e.g. the
    flapping ripple of the measured elevator), the moving average spans a whole number of
    ripple periods, which removes the ripple.

    **Arguments:**
    - `t`: time [s].
    - `x`: the measured input (`de` or `dr`).
    - `window`: length of each moving average [s].

    **Returns:** the smoothed input, same length as `x`.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    return _Input(t, x, window, QUIET_WINDOW).y


def _excitation(t, x, window=SMOOTH_WINDOW, quiet=QUIET_WINDOW) -> float:
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if x.shape[0] < 3 or not np.all(np.isfinite(x)):
        return 0.0
    return _Input(t, x, window, quiet).excitation()


def first_input_index(
    t: Float[ArrayLike, " n"],
    de_or_dr: Float[ArrayLike, " n"],
    *,
    window: float = SMOOTH_WINDOW,
    quiet: float = QUIET_WINDOW,
    n_sigma: float = 5.0,
    frac: float = 0.1,
    min_snr: float = 10.0,
) -> int | None:
    """The first sample of the manoeuvre: where the control input departs from its level.

    The input is low-pass smoothed (`smooth_input`: a moving average of about `window`
    seconds, applied twice; when the input ripples, e.g. the ~12 Hz flapping ripple of the
    measured elevator, the average spans a whole number of ripple periods, so the ripple
    does not count). Its initial level is the mean of the smoothed input over the first
    `quiet` seconds; its noise is the std the smoothing leaves of the input's white noise
    (estimated from second differences, robust to the ripple and to the input's steps).

    The input *departs* once it differs from its initial level by more than
    `max(n_sigma * noise, frac * range)` (`range`: max - min of the smoothed input). As the
    smoothing spreads a step over about `2 * window` seconds, the index returned is where
    the smoothed input (re-smoothed over a single ripple period, if it ripples) crosses half
    of its first excursion: for a step, pulse, doublet or 2-1-1 input, the sample where the
    raw input jumps, to within a sample or two.

    **Arguments:**
    - `t`: time [s], uniformly sampled.
    - `de_or_dr`: the measured control input (elevator `de` or rudder `dr`) [rad].
    - `window`: smoothing window [s]; a ripple is recognised above `1.5 / window` Hz.
    - `quiet`: initial window [s] giving the initial level.
    - `n_sigma`, `frac`: the departure threshold, see above.
    - `min_snr`: the input counts as varying only when its largest smoothed excursion
      exceeds `min_snr * noise`.

    **Returns:** the index of the first input sample, or `None` when the input does not vary
    (or holds NaN).
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(de_or_dr, dtype=float)
    n = x.shape[0]
    if n < 3 or t.shape[0] != n or not np.all(np.isfinite(x)):
        return None
    a = _Input(t, x, window, quiet)
    if a.peak <= a.tiny or a.peak <= min_snr * a.sigma:
        return None
    y, dev = a.y, a.dev
    thr = a.threshold(n_sigma, frac)
    above = np.flatnonzero(np.abs(dev) > thr)
    if above.size == 0:
        return None
    k = int(above[0])
    # The smoothing kernel spans about 2w samples: a step's smoothed ramp has ended within
    # 2w samples of the detection; its half-way point is the step.
    w = int(np.ceil(a.w))
    s = np.sign(dev[k])
    stop = min(n, k + 2 * w + 1)
    i = _half_crossing(dev, s, max(0, k - 2 * w), k + 1 + int(np.argmax(s * dev[k:stop])))
    i = k if i is None else i
    if a.period is not None and a.period < 0.75 * a.w:
        # Refine with one ripple period: the ramp is then only 2 periods long.
        p = int(np.ceil(a.period))
        dz = _smooth2(x, a.period, a.period) - a.level
        lo, hi = max(0, i - 3 * p), min(n, i + 3 * p + 1)
        j = _half_crossing(dz, s, lo, lo + int(np.argmax(s * dz[lo:hi])) + 1)
        if j is not None:
            i = j
    return int(i)


def input_column(columns: Mapping[str, ArrayLike], t: Float[ArrayLike, " n"]) -> str | None:
    """The control input that carries the manoeuvre: of `de` and `dr` (those present), the
    one whose smoothed excursion from its initial level is largest relative to its noise.

    **Returns:** `"de"`, `"dr"`, or `None` when neither is present.
    """
    present = [c for c in INPUT_COLUMNS if c in columns]
    if not present:
        return None
    t = np.asarray(t, dtype=float)
    scores = [_excitation(t, columns[c]) for c in present]
    return present[int(np.argmax(scores))]


def trim_window(t: Float[ArrayLike, " n"], first_input: int | None,
                quiet: float = QUIET_WINDOW) -> int:
    """The number of samples the trim is the mean of: those before `first_input` when they
    last at least `quiet` seconds, else the first `quiet` seconds (see `estimate_trim`)."""
    t = np.asarray(t, dtype=float)
    n = t.shape[0]
    stop = _window(t, quiet) if n else 0
    if first_input is not None and n and first_input < n:
        if t[first_input] - t[0] >= quiet * (1 - 1e-9) and first_input >= stop:
            stop = int(first_input)
    return max(1, min(stop, n))


def estimate_trim(
    flight_columns: Mapping[str, ArrayLike],
    t: Float[ArrayLike, " n"],
    *,
    first_input: int | None = None,
    quiet: float = QUIET_WINDOW,
) -> dict[str, float]:
    """The trim (linearisation point): the mean of every column over the quiet start.

    The quiet start is the samples before the first input (found with
    [`fwid.data.first_input_index`][] on `de` or `dr`, whichever varies). It must last at
    least `quiet` seconds (0.2 s, `QUIET_WINDOW`: 40 samples at 200 Hz, two to three wing
    beats of the DelFly, whose ripple the mean then averages out). When no input column
    exists, the input does not vary, or the quiet start is shorter than that, the first
    `quiet` seconds are used instead; reading a flight whose quiet start is too short warns
    ([`fwid.data.load_flight`][]), and its sidecar `NAME.json` can give the trim instead:
    `{"trim": {"u0": .., "w0": .., "theta0": ..}}`.

    **Arguments:**
    - `flight_columns`: the flight's columns by name (`t` may be included; it is skipped).
    - `t`: time [s].
    - `first_input`: the first-input index if already known (skips the search).
    - `quiet`: the minimum / fallback length of the quiet start [s].

    **Returns:** `{"<col>0": mean}` for every column (`u0`, `w0`, `theta0`, `q0`, `de0`, ...);
    columns with no finite mean over the quiet start are left out.
    """
    t = np.asarray(t, dtype=float)
    if first_input is None:
        col = input_column(flight_columns, t)
        if col is not None:
            first_input = first_input_index(t, flight_columns[col], quiet=quiet)
    stop = trim_window(t, first_input, quiet)
    trim = {}
    for name, values in flight_columns.items():
        if name == "t":
            continue
        x = np.asarray(values, dtype=float)[:stop]
        if x.size == 0:
            continue
        m = float(np.mean(x))
        if np.isfinite(m):
            trim[name + "0"] = m
    return trim
