"""How well a model reproduces the flapping: the amplitudes of the first flapping peaks
(the heights of Figure 12's peaks) and the share of the flapping band that is not at the
harmonics of the flapping frequency (what no series in the flapping phase, Eq. 12, can fit)."""

from __future__ import annotations

import numpy as np
from jaxtyping import ArrayLike, Float

from ..decomposition._filters import highpass
from ..decomposition._frequency import flapping_phase
from ..decomposition._split import edge_samples


def _phase_of(f, n: int, dt: float) -> np.ndarray:
    f = np.asarray(f, dtype=float)
    if f.ndim == 0:
        return 2 * np.pi * float(f) * dt * np.arange(n)
    if f.shape[-1] != n:
        raise ValueError(f"harmonic_amplitudes: f has {f.shape[-1]} samples, the signal {n}")
    return np.asarray(flapping_phase(f, dt))


def harmonic_amplitudes(
    x: Float[ArrayLike, "*channels n"],
    dt: float,
    f: float | Float[ArrayLike, " n"],
    n: int = 3,
    *,
    cutoff: float | None = 5.0,
    edge: float = 0.2,
) -> np.ndarray:
    """The amplitudes of the first `n` flapping peaks of `x` (the heights of Figure 12's peaks).

    The signal is high-passed at `cutoff` (zero-phase, to keep the slow body motion out), the
    first and last `edge` seconds are dropped (where the filter sees past the record's ends),
    and the rest is regressed on `1, sin(k phi), cos(k phi)`, `k = 1..n`, with `phi` the
    flapping phase; the
    amplitude of harmonic `k` is `sqrt(a_k^2 + b_k^2)`. For a steady flapping frequency this is
    the peak height of the amplitude spectrum; with a drifting frequency (given per sample)
    the smeared line is still counted whole, because the phase follows the drift.

    **Arguments:**
    - `x`: signals, time along the last axis.
    - `dt`: sample step [s].
    - `f`: the flapping frequency [Hz], a number or the measured `f` column (per sample).
    - `n`: the number of harmonics.
    - `cutoff`: high-pass cut-off [Hz] applied first (`None`: none).
    - `edge`: seconds dropped at each end after the high-pass (none for short records).

    **Returns:** the amplitudes, shape `(*channels, n)`, in the signal's unit.
    """
    x = np.asarray(x, dtype=float)
    m = x.shape[-1]
    phase = _phase_of(f, m, dt)
    if cutoff is not None:
        x = np.asarray(highpass(x, dt, cutoff, order=6))
        k = edge_samples(m, dt, edge)
        x, phase, m = x[..., k:m - k], phase[k:m - k], m - 2 * k
    cols = [np.ones(m)]
    for k in range(1, n + 1):
        cols += [np.sin(k * phase), np.cos(k * phase)]
    Phi = np.stack(cols, axis=-1)
    flat = x.reshape(-1, m).T  # (m, channels)
    coef, *_ = np.linalg.lstsq(Phi, flat, rcond=None)
    a, b = coef[1::2], coef[2::2]  # (n, channels)
    amp = np.sqrt(a**2 + b**2).T
    return amp.reshape(*x.shape[:-1], n)


def nonharmonic_share(
    z: np.ndarray, y: np.ndarray, dt: float, band: tuple[float, float]
) -> np.ndarray:
    """`100 E(z - y) / E(z)` per column, energies taken within `band` [Hz] (Parseval on the
    FFT): with `y` the fitted Fourier series, the share of the flapping-band energy that is
    not at the harmonics."""
    z, y = np.asarray(z, float), np.asarray(y, float)
    freqs = np.fft.rfftfreq(z.shape[0], dt)
    sel = (freqs >= band[0]) & (freqs <= band[1])
    ez = np.sum(np.abs(np.fft.rfft(z, axis=0)[sel]) ** 2, axis=0)
    er = np.sum(np.abs(np.fft.rfft(z - y, axis=0)[sel]) ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 100.0 * er / ez
