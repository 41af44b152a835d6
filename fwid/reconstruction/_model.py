"""The kinematic model the smoother uses, per axis: a slow part with white jerk plus the
flapping harmonics with slowly wandering coefficients, and a gyro bias.

State `[s, s', s'', A_1, B_1, .., A_K, B_K, b]`: `s` a position (m) or an attitude error
angle (rad) with its first two derivatives (white-jerk model, intensity `q_j`); the
acceleration of harmonic `k` of the flapping phase `phi(t) = 2 pi int f dt` is
`A_k cos(k phi) + B_k sin(k phi)` with `A_k`, `B_k` random walks (intensity `q_h`); `b` the
gyro's bias (constant). Position (attitude) and rate measure

    s + sum_k -(A_k cos k phi + B_k sin k phi) / (k W)^2,   W = 2 pi f
    s' + sum_k (A_k sin k phi - B_k cos k phi) / (k W) + b        (the gyro)

A harmonic at or above `HARMONIC_LIMIT` times the sample rate is left out (its rows are 0).
The model keeps the flapping content: up to the 3rd harmonic, the acceleration follows the
data with no low-pass at all, only the slow part is smoothed (cut-off `f_c`).
"""

from __future__ import annotations

import numpy as np

#: Flapping harmonics modelled (the paper's Fourier series, Sec. V: three).
HARMONICS = 3
#: A harmonic is modelled while k f < HARMONIC_LIMIT x the sample rate (below Nyquist).
HARMONIC_LIMIT = 0.45
#: Smoothing cut-offs of the slow part (Hz) and tracking bandwidths of the harmonic
#: coefficients (Hz) tried by maximum likelihood.
CUTOFFS = (0.5, 1.0, 2.0, 4.0, 8.0)
COEFF_BANDWIDTHS = (0.03, 0.1, 0.3, 1.0, 3.0)
#: Gyro noise over attitude noise (1/s, ratio of standard deviations) tried.
GYRO_RATIOS = (0.3, 1.0, 3.0, 10.0, 30.0, 100.0)


#: `transition` is the identity but for its leading `MIXING x MIXING` block.
MIXING = 3


def n_states(bias: bool) -> int:
    return 3 + 2 * HARMONICS + int(bias)


def transition(dt: float, bias: bool) -> np.ndarray:
    """`F` of the model: white jerk, random-walk coefficients, constant bias."""
    F = np.eye(n_states(bias))
    F[0, 1], F[0, 2], F[1, 2] = dt, dt**2 / 2, dt
    return F


def process_noise(dt: float, qj: float, qh: float, bias: bool) -> np.ndarray:
    """`Q` of the model for jerk intensity `qj` and coefficient intensity `qh`."""
    Q = np.zeros((n_states(bias),) * 2)
    Q[:3, :3] = qj * np.array([[dt**5 / 20, dt**4 / 8, dt**3 / 6],
                               [dt**4 / 8, dt**3 / 3, dt**2 / 2],
                               [dt**3 / 6, dt**2 / 2, dt]])
    i = np.arange(3, 3 + 2 * HARMONICS)
    Q[i, i] = qh * dt
    return Q


def intensities(dt: float, f_c: float, f_h: float, omega0: float) -> tuple[float, float]:
    """Jerk and coefficient intensities, per unit measurement variance, for a slow-part
    cut-off `f_c` (Hz: `q_j = dt (2 pi f_c)^6`, where the process's spectrum meets the
    noise's) and a coefficient bandwidth `f_h` (Hz: `q_h = dt W0^4 (2 pi f_h)^2`)."""
    return dt * (2 * np.pi * f_c) ** 6, dt * omega0**4 * (2 * np.pi * f_h) ** 2


def rows(phase, omega, rate, bias: bool, xp=np) -> dict:
    """The measurement and output rows `(..., N, n)` at each sample: `pos` (position or
    attitude), `vel` (rate, without the bias), `acc`, `gyro` (rate plus bias). `xp`: the
    array module (`numpy`, or `jax.numpy` inside a compiled program; `rate` may be traced)."""
    zero, one = xp.zeros_like(phase), xp.ones_like(phase)
    ok_f = xp.isfinite(omega) & (omega > 0)
    w_safe = xp.where(ok_f, omega, 1.0)
    pos, vel, acc = [one, zero, zero], [zero, one, zero], [zero, zero, one]
    for k in range(1, HARMONICS + 1):
        on = xp.where(ok_f & (k * w_safe / (2 * np.pi) < HARMONIC_LIMIT * rate), 1.0, 0.0)
        c, s, kw = xp.cos(k * phase), xp.sin(k * phase), k * w_safe
        pos += [on * -c / kw**2, on * -s / kw**2]
        vel += [on * s / kw, on * -c / kw]
        acc += [on * c, on * s]
    gyro = list(vel)
    if bias:
        pos, vel, acc, gyro = pos + [zero], vel + [zero], acc + [zero], gyro + [one]
    return {k: xp.stack(v, -1) for k, v in (("pos", pos), ("vel", vel), ("acc", acc),
                                             ("gyro", gyro))}


def slow_mask(bias: bool) -> np.ndarray:
    """1 on the white-jerk states, 0 on the harmonics' coefficients and the bias:
    `rows(...)["acc"] * slow_mask` is the slow part's acceleration."""
    return np.array([1.0] * 3 + [0.0] * (2 * HARMONICS) + [0.0] * int(bias))


def prior(n: int, bias: bool, scale: float) -> np.ndarray:
    """A diffuse prior covariance, in units of the measurement variance (`scale`: the
    variance a measurement is guessed to have)."""
    P0 = np.zeros((n, n))
    P0[np.arange(n), np.arange(n)] = [1.0, 1e2, 1e4] + [1e4] * (2 * HARMONICS) + [1.0] * int(bias)
    return P0 / scale


def phase_of(f: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Flapping phase `2 pi int f dt` (trapezoid) and angular frequency of a measured
    flapping frequency `f` (Hz), after a moving average over about one flapping cycle
    (the measurement noise of `f` would make the phase wander)."""
    f = np.asarray(f, dtype=float)
    good = np.isfinite(f) & (f > 0)
    if not good.any():
        return np.zeros_like(f), np.full_like(f, np.nan)
    f = np.where(good, f, np.median(f[good]))
    w = max(1, int(round(1.0 / (np.median(f) * dt))))
    if w > 1 and len(f) > 2 * w:
        pad = np.pad(f, (w // 2, w - 1 - w // 2), mode="edge")
        f = np.convolve(pad, np.ones(w) / w, mode="valid")
    omega = 2 * np.pi * f
    phase = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * dt)])
    return phase, omega
