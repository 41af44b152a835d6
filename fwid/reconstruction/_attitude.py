"""Attitude, body rates and angular accelerations: an error-state smoother on SO(3).

The attitude is `R = R_nom Exp(e)`, with `e` a 3-vector error about a nominal trajectory
`R_nom` (body axes, right perturbation). Per step, `R[k+1] = R[k] Exp(dt w[k] + dt^2/2 a[k])`
and `R_nom[k+1] = R_nom[k] Exp(dt w_nom[k])`, so to first order in `e`

    e[k+1] = e[k] + dt w[k] + dt^2/2 a[k] - dt w_nom[k]

(the rotation of `e` by `dt w_nom`, a part in ~1e-2 of an error that is itself ~1e-3 rad,
is left out, so the three axes are smoothed independently, vmapped). `w` and `a` follow
`_model` (white jerk plus the flapping harmonics); a recorded quaternion measures
`e = Log(R_nom^T R_meas)`, the gyro measures `w + b`. The smoothed `e` moves the nominal
(`R_nom <- R_nom Exp(e)`) and the smoother runs again about it (an iterated error-state
smoother, i.e. Gauss-Newton on the trajectory): the first pass starts from the recorded
attitude (gaps interpolated), two passes leave `e` at round-off of the noise.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._rotations import exp_so3, fill_gaps, log_so3, quat_to_matrix
from ._smoother import smooth_batch

#: Passes of the iterated smoother.
PASSES = 2
#: The attitude noise variance guessed for the diffuse prior (rad^2; ~0.15 deg).
ATTITUDE_SCALE = 1e-5


class Attitude(NamedTuple):
    """Smoothed attitude `R` `(B, N, 3, 3)` (body -> NED), body rates `w` and angular
    accelerations `a` `(B, N, 3)` (rad/s, rad/s^2), gyro bias `(B, 3)` or None, the noise
    levels chosen (`sigma`, `sigma_gyro` `(B, 3)`), the smoother's cut-off and coefficient
    bandwidth `(B, 3)` (Hz), and the chosen parameters for a later pass."""

    R: np.ndarray
    w: np.ndarray
    a: np.ndarray
    bias: np.ndarray | None
    sigma: np.ndarray
    sigma_gyro: np.ndarray | None
    cutoff: np.ndarray
    coeff_bandwidth: np.ndarray
    params: list


def nominal_rates(R: np.ndarray, dt: float) -> np.ndarray:
    """`w_nom[k] = Log(R[k]^T R[k+1]) / dt` `(B, N, 3)` (the last repeats)."""
    w = log_so3(np.swapaxes(R[:, :-1], -1, -2) @ R[:, 1:]) / dt
    return np.concatenate([w, w[:, -1:]], 1)


def smooth_attitude(quat, tracked, phase, omega, dt: float, *, gyro=None, gyro_mask=None,
                    start=None, passes: int = PASSES, params=None, lengths=None,
                    ends: bool = True) -> Attitude:
    """Smooth a batch of attitude records of one length.

    **Arguments:**
    - `quat` `(B, N, 4)`: recorded quaternions (body -> NED), NaN where lost;
    - `tracked` `(B, N)`: where recorded;
    - `phase`, `omega` `(B, N)`: flapping phase and angular frequency;
    - `dt`: sample step (s);
    - `gyro` `(B, N, 3)`, `gyro_mask` `(B, N)`: the gyro on the same time base, or None;
    - `start` `(B, N, 3, 3)`: a nominal to start from (default: the record, gaps filled);
    - `params`: noise parameters per problem (`B * 3`, take-major) to reuse; with a gyro,
      its noise is still searched (the motion's levels kept);
    - `passes`: passes of the iterated smoother;
    - `lengths` `(B,)`: each record's samples where records of several lengths are padded
      to one `N` (`tracked`, `gyro_mask` False there; see `smooth_batch`);
    - `ends`: the last pass holds each end's angular acceleration to the record's own
      (`smooth_batch`; the earlier passes only give the nominal).

    **Returns:** an `Attitude`.
    """
    B, N = tracked.shape
    Rm = quat_to_matrix(np.where(tracked[..., None], quat, [1.0, 0, 0, 0]))
    if start is None:
        start = quat_to_matrix(np.stack([fill_gaps(q, m) for q, m in zip(quat, tracked)]))
    nom = start
    mask3 = np.repeat(tracked, 3, axis=0)
    ph3, om3 = np.repeat(phase, 3, axis=0), np.repeat(omega, 3, axis=0)

    def axes(x):  # (B, N, 3) -> (B*3, N, 1), take-major, axis-minor
        return np.moveaxis(x, -1, 1).reshape(B * 3, N, 1)

    def back(x):  # (B*3, N, 1) -> (B, N, 3)
        return np.moveaxis(x.reshape(B, 3, N), 1, -1)

    g3 = gm3 = None
    if gyro is not None:
        g3, gm3 = axes(np.asarray(gyro, float)), np.repeat(gyro_mask, 3, axis=0)
    if gyro is not None and params is not None:
        params = [(p[0], p[1], None) for p in params]
    for k in range(passes):
        wn = nominal_rates(nom, dt)
        z = np.where(tracked[..., None], log_so3(np.swapaxes(nom, -1, -2) @ Rm), 0.0)
        sm = smooth_batch(axes(z), mask3, ph3, om3, dt, gyro=g3, gyro_mask=gm3,
                          ends=ends and k == passes - 1, u=axes(-dt * wn), scale=ATTITUDE_SCALE,
                          params=params,
                          lengths=None if lengths is None else np.repeat(lengths, 3))
        params = sm.params
        nom = nom @ exp_so3(back(sm.pos))
    per = lambda x: None if x is None else x.reshape(B, 3)  # noqa: E731
    return Attitude(nom, back(sm.vel), back(sm.acc),
                    None if sm.bias is None else sm.bias.reshape(B, 3),
                    per(sm.sigma), per(sm.sigma_gyro), per(sm.cutoff), per(sm.coeff_bandwidth),
                    params)
