"""The flapping frequency: estimated from a spectrum, integrated to a phase, cross-checked.

The paper measures the flapping frequency `f` in flight (11-13 Hz) and treats it as a known input of
the time-varying model (Section V.A, Eq. 12). Because `f` drifts during a manoeuvre (12.5-13.3 Hz
in Figure 4), the Fourier series is evaluated on the *phase* `phi(t) = int 2 pi f dt` rather than
on `2 pi f t`, so the model stays in phase with the wing beat (the two agree when `f` is constant).
"""

from __future__ import annotations

import functools as ft

import jax
import jax.numpy as jnp
import numpy as np
import scipy.fft
import scipy.signal
from jaxtyping import Array, ArrayLike, Float

from .._errors import FlightDataError

# Relative power a sub-harmonic peak (f/2, f/3 of the largest in-band peak) needs to be taken as
# the fundamental, and how far above the median in-band noise level it must stand.
_SUBHARMONIC_REL = 0.05
_SUBHARMONIC_SNR = 20.0
# Half width of the window, relative to the peak frequency, searched for sub-harmonics and over
# which the spectral centroid is taken (wide enough for a +-1 Hz drift at 12 Hz, narrow enough to
# exclude the second harmonic).
_HALF_WIDTH = 0.2
# Bins below this multiple of the median in-band level are noise and get no weight in the centroid.
_FLOOR = 3.0


@ft.cache
def _window(n: int) -> np.ndarray:
    return scipy.signal.windows.tukey(n, alpha=0.1)


def _estimate_1d(x, dt, band, oversample):
    n = x.shape[-1]
    # Least-squares straight line out (the mean and the slow trend of the cycle-averaged motion).
    s = jnp.asarray(np.linspace(-1.0, 1.0, n))
    xc = x - jnp.mean(x)
    xd = xc - s * (jnp.sum(s * xc) / jnp.sum(s * s))
    m = int(scipy.fft.next_fast_len(oversample * n, real=True))
    power = jnp.abs(jnp.fft.rfft(xd * _window(n), n=m)) ** 2
    df = 1.0 / (m * dt)
    freqs = jnp.arange(m // 2 + 1) * df
    lo, hi = band
    in_band = (freqs >= lo) & (freqs <= hi)
    p_band = jnp.where(in_band, power, 0.0)
    floor = jnp.nanmedian(jnp.where(in_band, power, jnp.nan))

    # Largest in-band peak; if it is a harmonic (a force can beat strongest at 2f), step down to a
    # clear peak at f/2 or f/3.
    k0 = jnp.argmax(p_band)
    f0 = k0 * df
    p0 = power[k0]
    chosen = f0
    for div in (2, 3):  # later (lower) accepted candidates win
        cand = f0 / div
        local = in_band & (jnp.abs(freqs - cand) <= _HALF_WIDTH * cand)
        p_local = jnp.max(jnp.where(local, power, 0.0))
        accept = (p_local >= _SUBHARMONIC_REL * p0) & (p_local >= _SUBHARMONIC_SNR * floor)
        chosen = jnp.where(accept, cand, chosen)
    local = in_band & (jnp.abs(freqs - chosen) <= _HALF_WIDTH * chosen)
    k1 = jnp.argmax(jnp.where(local, power, 0.0))

    # Parabolic interpolation of the log spectrum around the peak bin.
    km, kp = jnp.maximum(k1 - 1, 0), jnp.minimum(k1 + 1, m // 2)
    tiny = jnp.finfo(power.dtype).tiny
    a, b, c = (jnp.log(power[k] + tiny) for k in (km, k1, kp))
    denom = a - 2 * b + c
    delta = jnp.where(denom < 0, 0.5 * (a - c) / jnp.where(denom < 0, denom, -1.0), 0.0)
    f_peak = (k1 + jnp.clip(delta, -0.5, 0.5)) * df

    # Power centroid of the fundamental's line, over a window centred on the peak and symmetric
    # (clipped to the band): equals the peak for a steady tone and the (amplitude-weighted) mean
    # instantaneous frequency for a drifting one.
    half = jnp.minimum(jnp.minimum(_HALF_WIDTH * f_peak, f_peak - lo), hi - f_peak)
    near = jnp.abs(freqs - f_peak) <= half
    weight = jnp.where(near, jnp.maximum(power - _FLOOR * floor, 0.0), 0.0)
    total = jnp.sum(weight)
    centroid = jnp.sum(weight * freqs) / jnp.where(total > 0, total, 1.0)
    return jnp.where(total > 0, centroid, f_peak)


def estimate_flapping_frequency(
    x: Float[ArrayLike, "*channels n"],
    dt: float,
    *,
    band: tuple[float, float] = (5.0, 30.0),
    oversample: int = 8,
) -> Float[Array, "*channels"]:
    """Estimate the (mean) flapping frequency from the spectrum of a force or rate signal.

    The straight-line trend is removed, the record is tapered (Tukey window, 10 %), zero-padded to
    `oversample` times its length and transformed. The largest peak in `band` is located (if a clear
    peak stands at a half or a third of its frequency, that one is taken as the fundamental: a
    force may beat strongest at twice the flapping frequency), refined by parabolic interpolation of
    the log spectrum, and the estimate is the power centroid of that spectral line within +-20 % of
    the peak, after removing the noise floor. For a steady tone that is the peak frequency (to about
    0.01 Hz on 4 s of data, a 25th of the bin width `1/T`); for a drifting frequency it is the mean
    instantaneous frequency (the first moment of the power spectrum of `a cos(phi(t))` is the
    `a^2`-weighted mean of `phi'(t) / 2 pi`).

    Jit-able and vmap-able (`band` and `oversample` static).

    **Arguments:**

    - `x`: a signal that beats at the flapping frequency (e.g. the force `X` or `Z`, the pitch rate
      `q`, the elevator `de`), time along the last axis; leading axes are independent channels.
    - `dt`: sample step [s].
    - `band`: the frequency range [Hz] searched for the fundamental (Section III.B: 11-13 Hz).
    - `oversample`: zero-padding factor of the FFT.

    **Returns:** the frequency [Hz] as a 0-d array per channel (`float(...)` for a Python number).
    """
    x = jnp.asarray(x, dtype=float)
    band = (float(band[0]), float(band[1]))
    return _estimate(x, dt, band, int(oversample))


@ft.partial(jax.jit, static_argnums=(2, 3))
def _estimate(x, dt, band, oversample):
    fn = jnp.vectorize(lambda v: _estimate_1d(v, dt, band, oversample), signature="(n)->()")
    return fn(x)


def flapping_phase(
    f: Float[ArrayLike, "*channels n"],
    dt: float | Float[ArrayLike, ""],
    *,
    phase0: float | Float[ArrayLike, "*channels"] = 0.0,
) -> Float[Array, "*channels n"]:
    """The flapping phase `phi(t) = phase0 + int_0^t 2 pi f(s) ds` (trapezoidal rule).

    The time-varying model of Eq. (12), `sum_n a_n sin(n phi) + b_n cos(n phi)`, driven by this
    phase stays in step with a drifting flapping frequency; for constant `f` it is Eq. (12) exactly
    (`phi = 2 pi f t`). Exact for a piecewise-linear `f`. Jit-able, vmap-able, differentiable.

    **Arguments:**

    - `f`: flapping frequency [Hz] at each sample, time along the last axis.
    - `dt`: sample step [s].
    - `phase0`: phase at the first sample [rad].

    **Returns:** the phase [rad], same shape as `f`, `phase0` at the first sample.
    """
    return _phase(jnp.asarray(f, dtype=float), dt, phase0)


@jax.jit
def _phase(f, dt, phase0):
    increments = jnp.pi * dt * (f[..., 1:] + f[..., :-1])
    phase = jnp.concatenate(
        [jnp.zeros(f.shape[:-1] + (1,), dtype=f.dtype), jnp.cumsum(increments, axis=-1)], axis=-1
    )
    return phase + jnp.asarray(phase0, dtype=f.dtype)[..., None]


def check_flapping_frequency(
    f_column: Float[ArrayLike, " n"],
    x: Float[ArrayLike, " n"],
    dt: float,
    *,
    tolerance: float = 0.1,
    band: tuple[float, float] = (5.0, 30.0),
    name: str | None = None,
) -> str:
    """Compare a measured flapping-frequency column with the frequency at which `x` beats.

    **Arguments:**

    - `f_column`: the measured flapping frequency `f` [Hz] (the flight-data format).
    - `x`: a signal beating at the flapping frequency (a force, a rate, the elevator).
    - `dt`: sample step [s].
    - `tolerance`: largest accepted relative difference between the mean of `f_column` and the
      spectral estimate of [`fwid.decomposition.estimate_flapping_frequency`][] (default 10 %).
    - `band`: frequency range [Hz] searched for the spectral peak.
    - `name`: where the data come from (e.g. the flight's file name), for the message.

    **Returns:** a one-line message giving both frequencies and their difference.

    **Raises:** `fwid.FlightDataError` if `f_column` is not finite and positive, or if the two
    frequencies differ by more than `tolerance` (the message suggests the likely cause: `f` in
    rad/s, a harmonic, or a column that does not belong to the signal).
    """
    where = f"{name}: " if name else ""
    f_np = np.asarray(f_column, dtype=float)
    if f_np.size == 0 or not np.all(np.isfinite(f_np)) or not np.all(f_np > 0):
        raise FlightDataError(
            f"{where}flapping frequency column 'f' must be finite and positive [Hz]; "
            f"it has {np.sum(~np.isfinite(f_np))} non-finite and {np.sum(f_np <= 0)} non-positive "
            "values"
        )
    measured = float(np.mean(f_np))
    spectral = float(estimate_flapping_frequency(x, dt, band=band))
    rel = (measured - spectral) / spectral
    message = (
        f"{where}flapping frequency: column 'f' mean {measured:.3f} Hz, spectral estimate "
        f"{spectral:.3f} Hz ({100 * rel:+.1f} %)"
    )
    if abs(rel) <= tolerance:
        return message
    ratio = measured / spectral
    if abs(ratio - 2 * np.pi) < 0.1 * 2 * np.pi:
        hint = "'f' looks like rad/s: divide it by 2*pi"
    elif any(abs(ratio - r) < 0.05 * r for r in (0.5, 1 / 3, 2.0, 3.0)):
        hint = (
            "one of the two is a harmonic of the other: check 'f', or estimate from a signal "
            "whose fundamental dominates (e.g. X or q)"
        )
    else:
        hint = "check the units of 'f' and that it belongs to this flight"
    raise FlightDataError(f"{message}, more than {100 * tolerance:.0f} % apart: {hint}")
