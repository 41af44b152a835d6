"""Aerodynamic loads reconstructed from the measured motion, as the paper does (Sec. III.A):
the linearised EOM (Eqs. 7-8) solved for the aerodynamic terms, with the state derivatives
from numerical differentiation."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy import signal

from ._delfly import DELFLY, DelFly

#: Low-pass cut-off [Hz] (zero-phase, 4th-order Butterworth) of the reconstructed loads of a
#: noisy flight: above the 3rd flapping harmonic (~40 Hz), as in the paper (Sec. III.B).
LOAD_CUTOFF = 60.0

_CENTRAL = {
    1: np.array([-1 / 2, 0, 1 / 2]),
    2: np.array([1 / 12, -2 / 3, 0, 2 / 3, -1 / 12]),
    3: np.array([-1 / 60, 3 / 20, -3 / 4, 0, 3 / 4, -3 / 20, 1 / 60]),
    4: np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280]),
}


def derivative(x, dt: float) -> np.ndarray:
    """Time derivative of uniformly sampled `x` (along axis 0): 8th-order central
    differences in the interior (gain within 0.5 % of the exact derivative up to 0.19 times
    the sample rate, e.g. the 3rd flapping harmonic, 37.5 Hz, at 200 Hz), lower orders
    towards the ends, one-sided 2nd order at the first and last sample."""
    x = np.asarray(x, dtype=float)
    n = x.shape[0]
    d = np.gradient(x, dt, axis=0, edge_order=2) if n >= 3 else np.gradient(x, dt, axis=0)
    for half in (2, 3, 4):
        if n < 2 * half + 1:
            break
        # acc[i - half] = central difference of order 2*half at sample i
        acc = sum(cj * x[j : n - 2 * half + j] for j, cj in enumerate(_CENTRAL[half]) if cj)
        if half == 4:
            d[half : n - half] = acc / dt
        else:  # only where the next order does not fit
            d[half] = acc[0] / dt
            d[n - 1 - half] = acc[-1] / dt
    return d


def reconstruct_loads(
    columns: Mapping[str, np.ndarray],
    rate: float,
    trim: Mapping[str, float],
    vehicle: DelFly = DELFLY,
    cutoff: float | None = LOAD_CUTOFF,
) -> dict[str, np.ndarray]:
    """Aerodynamic loads "as reconstructed from the measured motion": the linearised EOM
    (Eqs. 7-8) solved for the aerodynamic terms, with the state derivatives from
    `derivative` (numerical differentiation of the measured states):

        X = X0 + m (du/dt + w0 dq + g cos(theta0) dtheta),        X0 = m g sin(theta0)
        Z = Z0 + m (dw/dt - u0 dq + g sin(theta0) dtheta),        Z0 = -m g cos(theta0)
        M = Iy dq/dt
        Y = m (dv/dt - w0 dp + u0 dr - g cos(theta0) dphi)
        L = Ix dp/dt - Ixz dr/dt
        N = Iz dr/dt - Ixz dp/dt

    (`d` = perturbation from `trim`). With `cutoff` [Hz] the result is low-pass filtered
    (4th-order Butterworth, forward-backward: zero phase) to tame the noise that
    differentiation amplifies; `None` skips it (noise-free flights).
    """
    m, g, Ix, Iy, Iz, Ixz = vehicle.mass, vehicle.g, vehicle.Ix, vehicle.Iy, vehicle.Iz, vehicle.Ixz
    u0, w0, th0 = trim["u0"], trim["w0"], trim["theta0"]
    dt = 1.0 / rate

    def pert(c):
        return np.asarray(columns[c], dtype=float) - trim.get(c + "0", 0.0)

    dq, dtheta, dp, dr, dphi = pert("q"), pert("theta"), pert("p"), pert("r"), pert("phi")
    ddot = derivative(np.stack([pert(c) for c in ("q", "u", "w", "p", "r", "v")], axis=1), dt)
    qd, ud, wd, pd, rd, vd = ddot.T
    X = m * g * np.sin(th0) + m * (ud + w0 * dq + g * np.cos(th0) * dtheta)
    Z = -m * g * np.cos(th0) + m * (wd - u0 * dq + g * np.sin(th0) * dtheta)
    M = Iy * qd
    Y = m * (vd - w0 * dp + u0 * dr - g * np.cos(th0) * dphi)
    L = Ix * pd - Ixz * rd
    N = Iz * rd - Ixz * pd
    out = {"X": X, "Y": Y, "Z": Z, "L": L, "M": M, "N": N}
    if cutoff is not None and len(X) > 30:
        sos = signal.butter(4, min(cutoff, 0.45 * rate), fs=rate, output="sos")
        out = {k: signal.sosfiltfilt(sos, v) for k, v in out.items()}
    return out
