"""Flapping harmonics below their own noise shrunk toward zero (empirical Bayes).

A harmonic that the take cannot resolve (the roll and yaw flapping of a longitudinal flight
tracked without a gyro: a hundredth of a degree under 0.15 degree of pose noise) is estimated
by the smoother as noise, as large as the noise allows. The loads then carry it, multiplied by
the large flapping pitch rate in `w x I w` and the product of inertia: an error in `L` and
`N` that the slow pitch motion modulates, which the diagnosis would read as a coupling.

It is applied to the smoothed body rates and angular accelerations (`_pipeline._shrunk`),
where such errors reach the loads through products; the position's harmonics, which reach
the forces linearly, are left as the smoother has them (shrinking them would trade their
noise for a loss of the third harmonic). Each harmonic's constant part is estimated by least
squares on the smoothed signal's flapping part (its cos and sin coefficients `c`), and
scaled by the shrinkage factor of a Gaussian prior whose variance is estimated from the same
numbers,
`g = max(0, 1 - 2 V / |c|^2)` with `V` the variance of one coefficient from the measurement
noise alone (`2 sigma^2 / N` for `N` samples of noise `sigma`): a harmonic well above its
noise keeps `g ~ 1`, one at its noise goes to zero.
"""

from __future__ import annotations

import numpy as np
from jaxtyping import Float

from ._model import HARMONICS
from ._smoother import _cycle_mean, cycle_samples


def coefficient_variance(sigma: Float[np.ndarray, " c"], samples: int) -> Float[np.ndarray, " c"]:
    """Variance of one cos or sin coefficient fitted to `samples` samples of white noise of
    standard deviation `sigma`."""
    return 2.0 * np.asarray(sigma, float) ** 2 / max(int(samples), 1)


def shrink_harmonics(series: list, phase: Float[np.ndarray, " n"], omega: Float[np.ndarray, " n"],
                     variance: Float[np.ndarray, "k c"], dt: float) -> tuple[list, np.ndarray]:
    """Shrink the constant part of each flapping harmonic of a smoothed signal.

    **Arguments:**
    - `series`: the signal `(N, c)` followed by its time derivatives (each `(N, c)`);
    - `phase`, `omega` `(N,)`: flapping phase and angular frequency;
    - `variance` `(HARMONICS, c)`: the noise variance of one coefficient of harmonic `k` of the
      signal (`series[0]`);
    - `dt`: sample step (s); the slow part is the signal averaged over a flapping cycle.

    **Returns:** the series with each harmonic's part scaled by its factor `g`, and `g`
    `(HARMONICS, c)`.
    """
    y = np.asarray(series[0], float)
    if not np.isfinite(omega).any():
        return list(series), np.ones_like(variance)
    good = np.all(np.isfinite(y), 1) & np.isfinite(omega)
    cycle = max(1, cycle_samples(omega, dt, 1))
    fast = y - _cycle_mean(y, cycle)
    edge = min(2 * cycle, len(y) // 4)  # where the average's edges leave slow motion in `fast`
    good[:edge] = good[len(y) - edge:] = False
    ks = np.arange(1, HARMONICS + 1)
    kp = ks[None, :] * phase[:, None]  # (N, K)
    B = np.concatenate([np.cos(kp), np.sin(kp)], 1)  # (N, 2K)
    coef = np.linalg.lstsq(B[good], fast[good], rcond=None)[0]  # (2K, c)
    a, b = coef[:len(ks)], coef[len(ks):]
    power = a**2 + b**2
    g = np.where(power > 0, np.clip(1.0 - 2.0 * variance / np.maximum(power, 1e-300), 0.0, 1.0), 1.0)
    cut_a, cut_b = (1 - g) * a, (1 - g) * b
    out = []
    kw = ks[None, :] * omega[:, None]  # d(k phi)/dt
    for order, x in enumerate(series):
        # the order-th derivative of cos(k phi), sin(k phi) at a slowly changing frequency
        c, s = np.cos(kp + order * np.pi / 2), np.sin(kp + order * np.pi / 2)
        scale = kw**order
        out.append(np.asarray(x, float) - (scale * c) @ cut_a - (scale * s) @ cut_b)
    return out, g
