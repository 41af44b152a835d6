"""Residual colour measured at the data's own bandwidth, not at one sample.

The output-error likelihood of Eqs. (10)-(11) assumes white measurement noise. Whether the
residuals are white can only be judged at the resolution the data actually have: fwid's
cycle-averaged flights are low-passed (Sec. III.B, 5 Hz) and sampled at 200 Hz, so even pure
measurement noise is correlated over ~20 samples and its autocorrelation at one sample is
0.997 (the DelFly demo). [`bandwidth_lag`][] finds, per output, the frequency below which
99 % of the power of the measured output's first difference lies (Hann-windowed against
leakage; the difference flattens the spectrum, so white noise up to Nyquist puts that
frequency near Nyquist and a pre-filter puts it at the filter's edge), and the number of
samples `k = round(1 / (2 f_b dt))` that spans half a period there: samples `k` apart are as
independent as the data allow. [`colour_at_bandwidth`][] is the residuals' largest
autocorrelation over the lags `k .. 3k`: pre-filtered noise has only the filter's side lobes
there, while model error stays correlated, or, narrow-band at the data's top frequency (where
the lag `k` is half its period), comes back to ~1 at `2k`.

Measured with `benchmarks/textbook_cases.py` and the DelFly demo (`fwid simulate`, lon,
flights 0 and 1): the low-passed DelFly flights' residuals give at most 0.33 (lags 20-46
samples; at one sample 0.997), the textbook records' model error 0.97 (FVSysID TC01, lags
1-3), 0.998 (TC04, lag 1) and 0.87-0.90 (SIDPAC Twin Otter, lags 3-6).
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float, Int

#: The fraction of the differenced output's power below the data's bandwidth.
BANDWIDTH_POWER = 0.99


def bandwidth_lag(z: Float[Array, "n ny"], mask: Float[Array, " n"],
                  power: float = BANDWIDTH_POWER) -> Int[Array, " ny"]:
    """Per output, the samples spanning half a period at the data's bandwidth: `round(1 / (2
    f_b))` with `f_b` (cycles per sample) the frequency below which `power` of the power of
    the first difference of `z` lies (padding excluded); at least 1, at most a quarter of
    the record."""
    n = z.shape[0]
    both = (mask[1:] * mask[:-1])[:, None]
    m = jnp.sum(both)  # valid differences: the first m (padding is at the end)
    d = (z[1:] - z[:-1]) * both
    d = (d - jnp.sum(d, axis=0) / jnp.maximum(m, 1.0)) * both
    i = jnp.arange(n - 1)
    d = d * (0.5 - 0.5 * jnp.cos(2 * jnp.pi * i / jnp.maximum(m - 1, 1)))[:, None]
    P = jnp.abs(jnp.fft.rfft(d, n=2 * n, axis=0)) ** 2  # (f, ny), zero-padded: fine grid
    f = jnp.fft.rfftfreq(2 * n)  # cycles per sample
    c = jnp.cumsum(P, axis=0) / jnp.maximum(jnp.sum(P, axis=0), 1e-300)
    fb = f[jnp.argmax(c >= power, axis=0)]
    k = jnp.round(0.5 / jnp.maximum(fb, 1e-12))
    return jnp.clip(k, 1, jnp.maximum(jnp.sum(mask) // 4, 1)).astype(int)


def colour_at_bandwidth(v: Float[Array, "n ny"], z: Float[Array, "n ny"],
                        mask: Float[Array, " n"]) -> Float[Array, " ny"]:
    """Each output's largest residual autocorrelation `sum v_i v_i+tau / sum v_i^2` over the
    lags `tau = k .. 3k`, `k` its [`bandwidth_lag`][] (padding excluded): about 0 for
    measurement noise, white or pre-filtered, near 1 when model error or process noise makes
    the residuals."""
    n = v.shape[0]
    v = v * mask[:, None]
    F = jnp.fft.rfft(v, n=2 * n, axis=0)
    r = jnp.fft.irfft(jnp.abs(F) ** 2, n=2 * n, axis=0)[:n]  # (n, ny): lags 0 .. n-1
    k = bandwidth_lag(z, mask)[None, :]
    tau = jnp.arange(n)[:, None]
    window = (tau >= k) & (tau <= 3 * k)
    return jnp.max(jnp.where(window, r, -jnp.inf), axis=0) / jnp.maximum(r[0], 1e-300)
