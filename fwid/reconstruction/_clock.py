"""The autopilot's clock against the tracking clock, and its signals on the take's time base.

`t_tracking = t_onboard + offset`. The offset is found from the gyro and the body rates of
the attitude smoothed without it, in two steps:

1. coarse, over every lag that leaves at least `min_overlap` seconds in common: the
   normalised cross-correlation (summed over p q r) of both signals low-passed below
   `COARSE_CUTOFF` times the flapping frequency (the cycle-averaged manoeuvre: one peak,
   not one per flapping cycle), on the take's sample grid; of the peaks within `TIE` of the
   best correlation (a manoeuvre repeated), the one with the longest overlap;
2. fine, to a fraction of a sample: the offset that minimises the squared difference of the
   full-band gyro (spline-interpolated at `t - offset`, less its mean difference per axis:
   the bias) and the smoothed rates, within 1.5 samples of the coarse one.

Its quality: `std` (s), `corr` (the correlation of the two aligned signals) and `rms` (rad/s,
their residual). `std` combines the fit's own (from the curvature of that cost, as if the
residual were white) with the limit the tracking sets, when its attitude noise `sigma` is
given: a shift `tau` moves the recorded attitude by `w tau`, so no estimate from the take can
beat `1 / sqrt(sum_t sum_axes w^2 / sigma^2)` (the Cramer-Rao bound; 0.2-0.3 ms for 5 s of
flapping flight at 0.15 degree). The rates smoothed from the attitude carry exactly that
noise, correlated over the take, which the curvature alone does not see.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# scipy is imported where used: a take without an autopilot log never needs it (and its
# import is a good part of a short run)

#: Low-pass of the coarse search, as a fraction of the flapping frequency.
COARSE_CUTOFF = 0.35
#: Coarse correlations this close to the best are a tie, given to the longer overlap.
TIE = 0.01
#: Shortest overlap (s) of take and log accepted.
MIN_OVERLAP = 2.0


class ClockOffset(NamedTuple):
    offset: float   # s, t_tracking = t_onboard + offset
    std: float      # s
    corr: float
    rms: float      # rad/s
    given: bool


def lowpass(t: np.ndarray, x: np.ndarray, cutoff: float) -> np.ndarray:
    """Zero-phase 8th-order Butterworth low-pass of uniformly sampled `x` (along axis 0),
    or `x` itself when `cutoff` is at or above 0.9 x Nyquist."""
    from scipy import signal

    rate = (len(t) - 1) / (t[-1] - t[0])
    if cutoff >= 0.45 * rate or len(t) < 60:
        return x
    sos = signal.butter(8, cutoff, fs=rate, output="sos")
    return signal.sosfiltfilt(sos, x, axis=0)


def resample(t_src: np.ndarray, x: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """`x` (on the uniform `t_src`) at the times `t_dst` (uniform): low-passed below 0.45
    times the destination rate first when the source is faster (no aliasing), then a cubic
    spline; NaN outside `t_src`."""
    from scipy import interpolate

    rate_dst = (len(t_dst) - 1) / (t_dst[-1] - t_dst[0])
    x = lowpass(t_src, np.asarray(x, float), 0.45 * rate_dst)
    out = interpolate.CubicSpline(t_src, x, axis=0, extrapolate=False)(t_dst)
    return out


def _xcorr(a: np.ndarray, b: np.ndarray, min_n: int):
    """Normalised cross-correlation of `a` `(Na, 3)` against `b` `(Nb, 3)`, summed over
    the columns: `(lags, values)`, lag `l` pairing `a[n + l]` with `b[n]`."""
    from scipy import signal

    num = sum(signal.correlate(a[:, i], b[:, i], mode="full", method="fft") for i in range(3))
    ones_a, ones_b = np.ones(len(a)), np.ones(len(b))
    ea = signal.correlate(np.sum(a**2, 1), ones_b, mode="full", method="fft")
    eb = signal.correlate(ones_a, np.sum(b**2, 1), mode="full", method="fft")
    n = signal.correlate(ones_a, ones_b, mode="full", method="fft")
    lags = signal.correlation_lags(len(a), len(b), mode="full")
    val = num / np.sqrt(np.maximum(ea, 1e-30) * np.maximum(eb, 1e-30))
    return lags, np.where(np.round(n) >= min_n, val, -np.inf), n


def find_offset(t: np.ndarray, w: np.ndarray, t_log: np.ndarray, gyro: np.ndarray,
                f0: float, *, given: float | None = None,
                min_overlap: float = MIN_OVERLAP,
                sigma: np.ndarray | None = None) -> ClockOffset | None:
    """The offset of the autopilot's clock (see the module docstring).

    **Arguments:**
    - `t`, `w` `(N, 3)`: the take's time base and the body rates smoothed without the gyro;
    - `t_log`, `gyro` `(M, 3)`: the log's clock and its gyro;
    - `f0`: the flapping frequency (Hz), for the coarse low-pass;
    - `given`: an offset to use instead of searching (its quality is still measured);
    - `min_overlap`: the shortest overlap (s) a lag may leave;
    - `sigma` `(3,)`: the attitude's noise (rad per axis) behind `w`, for the bound on `std`.

    **Returns:** a `ClockOffset`, or None when no lag leaves `min_overlap` in common.
    """
    from scipy import interpolate, optimize, signal

    dt = (t[-1] - t[0]) / (len(t) - 1)
    spline = interpolate.CubicSpline(t_log, lowpass(t_log, gyro, 0.45 / dt), axis=0,
                                     extrapolate=False)
    if given is None:
        # inside the log: a last point past its end by round-off is NaN in the spline
        grid = np.minimum(np.arange(t_log[0], t_log[-1] + 1e-9, dt), t_log[-1])
        cut = COARSE_CUTOFF * (f0 if np.isfinite(f0) and f0 > 0 else 12.0)
        a = lowpass(t, w - w.mean(0), cut)
        b = lowpass(grid, spline(grid) - spline(grid).mean(0), cut)
        lags, val, n = _xcorr(a, b, int(min_overlap / dt))
        if not np.isfinite(val).any():
            return None
        # a near-tie (a repeated manoeuvre) goes to the lag with the longer overlap
        peaks, _ = signal.find_peaks(np.where(np.isfinite(val), val, -2.0))
        best = int(np.argmax(val))
        near = [p for p in peaks if val[p] >= val[best] - TIE]
        if near:
            best = max(near, key=lambda p: (n[p], val[p]))
        coarse = t[0] - grid[0] + lags[best] * dt
    else:
        coarse = given

    inside = (t - coarse - 2 * dt >= t_log[0]) & (t - coarse + 2 * dt <= t_log[-1])
    if inside.sum() * dt < min_overlap:
        return None

    def residual(tau):
        d = spline(t[inside] - tau) - w[inside]
        return d - d.mean(0), inside

    def cost(tau):
        return np.mean(residual(tau)[0] ** 2)

    if given is None:
        res = optimize.minimize_scalar(cost, bounds=(coarse - 1.5 * dt, coarse + 1.5 * dt),
                                       method="bounded", options={"xatol": 1e-6 * dt})
        tau = float(res.x)
    else:
        tau = float(given)
    d, ok = residual(tau)
    h = 0.05 * dt
    n = ok.sum()
    curv = (cost(tau + h) - 2 * cost(tau) + cost(tau - h)) / h**2 * 3 * n
    s2 = np.sum(d**2) / max(3 * n - 4, 1)
    std = float(np.sqrt(2 * s2 / curv)) if np.isfinite(curv) and curv > 0 else float("nan")
    if sigma is not None:
        info = float(np.sum(w[ok] ** 2 / np.asarray(sigma, float) ** 2))
        std = float(np.hypot(std, 1.0 / np.sqrt(info))) if info > 0 else std
    wc = w[ok] - w[ok].mean(0)
    gc = wc + d
    corr = float(np.sum(wc * gc) / np.sqrt(np.sum(wc**2) * np.sum(gc**2)))
    return ClockOffset(tau, std, corr, float(np.sqrt(np.mean(d**2))), given is not None)
