"""Checks of a reconstructed take against the data: the frame, and the residuals.

**The frame check.** A flying vehicle's aerodynamic force holds it up: averaged over the
take, the specific force `(X, Y, Z) / m` in body axes points up the body, along `-z` (a
rotorcraft, a DelFly in hover) or forward and up (a DelFly in slow forward flight, pitched
~70 deg: mostly `+x`). When the tracking frame is not the one the reader was told, gravity
is subtracted along the wrong axis and that mean points sideways or down the body. The take
is refused when the mean is larger than `FRAME_MIN` g and either its sideways part exceeds
`FRAME_SIDE` of it or it points into the lower-aft half (`(f_x - f_z) < 0`). A frame whose
world and body axes are both relabelled alike (say a y-up take read as z-up) is the same as a
rotated world, which no check can see while the vehicle keeps a constant attitude.
"""

from __future__ import annotations

import numpy as np

from .._errors import FlightDataError
from ._rotations import log_so3, quat_to_matrix

FRAME_MIN = 0.3
FRAME_SIDE = 0.7


def check_frame(specific_force: np.ndarray, g: float, take) -> None:
    """Refuse a take whose mean body-axis specific force `(N, 3)` (m/s^2) contradicts its
    frame (module docstring), with a `FlightDataError` naming the take and the fix."""
    f = np.mean(specific_force, 0)
    size = float(np.linalg.norm(f))
    if size < FRAME_MIN * g:
        return
    d = f / size
    if abs(d[1]) > FRAME_SIDE or d[0] - d[2] < 0:
        raise FlightDataError(
            f"{take.path}: the aerodynamic force averages ({f[0]:.3g}, {f[1]:.3g}, {f[2]:.3g}) "
            "m/s^2 per kg in body axes: it does not hold the vehicle up (it points sideways or "
            f"down the body), so gravity lies along a wrong axis of the {take.frame} frame read; "
            "give the take's frame with --frame ned|y-up|z-up (and the quaternion body -> Earth)")


def residuals(pos, quat, tracked, pos_s, R_s, w_s, gyro=None, bias=None) -> dict:
    """Consistency of the smoothed motion with the record: rms of recorded minus smoothed
    position (m, over the three axes) and attitude (rad, per body axis, `Log(R_s^T R)`),
    and of the gyro less its bias minus the smoothed rates (rad/s, per axis)."""
    ok = tracked
    dp = pos[ok] - pos_s[ok]
    Rm = quat_to_matrix(quat[ok])
    de = log_so3(np.swapaxes(R_s[ok], -1, -2) @ Rm)
    out = {"position_rms_m": float(np.sqrt(np.mean(dp**2))),
           "attitude_rms_rad": [float(v) for v in np.sqrt(np.mean(de**2, 0))],
           "gyro_rms_rad_s": None}
    if gyro is not None:
        dg = gyro - (0 if bias is None else bias) - w_s
        out["gyro_rms_rad_s"] = [float(v) for v in np.sqrt(np.mean(dg**2, 0))]
    return out
