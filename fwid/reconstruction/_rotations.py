"""Rotations in numpy: quaternions (Hamilton, scalar first, body -> Earth), rotation
matrices, the exponential map of SO(3), 3-2-1 Euler angles, and the maps of y-up and z-up
tracking frames to north-east-down."""

from __future__ import annotations

import numpy as np

#: Tracking frame -> north-east-down, for the world and the body axes alike (the guide
#: on raw recordings): y-up (Motive: X north, Y up, Z east) and z-up (Vicon: X north, Y west, Z up).
FRAMES = {
    "ned": np.eye(3),
    "y-up": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
    "z-up": np.diag([1.0, -1.0, -1.0]),
}


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices `(..., 3, 3)` of unit quaternions `(..., 4)` `[w, x, y, z]`
    (Hamilton): `R @ v_body = v_earth`."""
    q = np.asarray(q, dtype=float)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def tracked_matrices(q: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Rotation matrices `(n, 3, 3)` of quaternions `(n, 4)` `[w, x, y, z]`, normalised, the
    identity on the rows that are not `ok` (lost: whatever they hold)."""
    safe = np.where(ok[:, None], q, [1.0, 0.0, 0.0, 0.0])
    return quat_to_matrix(safe / np.linalg.norm(safe, axis=1, keepdims=True))


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternions `[w, x, y, z]` (w >= 0) of rotation matrices `(..., 3, 3)`
    (Shepperd's method: the largest of the four squared components first)."""
    R = np.asarray(R, dtype=float)
    tr = np.trace(R, axis1=-2, axis2=-1)
    d = np.stack([tr, R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]], -1)
    k = np.argmax(d, axis=-1)
    q = np.empty(R.shape[:-2] + (4,))
    s = np.sqrt(np.maximum(1 + 2 * np.take_along_axis(d, k[..., None], -1)[..., 0] - tr, 1e-300))
    # k == 0: w largest
    c = [
        (s / 2, (R[..., 2, 1] - R[..., 1, 2]) / (2 * s), (R[..., 0, 2] - R[..., 2, 0]) / (2 * s),
         (R[..., 1, 0] - R[..., 0, 1]) / (2 * s)),
        ((R[..., 2, 1] - R[..., 1, 2]) / (2 * s), s / 2, (R[..., 0, 1] + R[..., 1, 0]) / (2 * s),
         (R[..., 0, 2] + R[..., 2, 0]) / (2 * s)),
        ((R[..., 0, 2] - R[..., 2, 0]) / (2 * s), (R[..., 0, 1] + R[..., 1, 0]) / (2 * s), s / 2,
         (R[..., 1, 2] + R[..., 2, 1]) / (2 * s)),
        ((R[..., 1, 0] - R[..., 0, 1]) / (2 * s), (R[..., 0, 2] + R[..., 2, 0]) / (2 * s),
         (R[..., 1, 2] + R[..., 2, 1]) / (2 * s), s / 2),
    ]
    for i in range(4):
        sel = k == i
        q[sel] = np.stack([np.asarray(v)[sel] for v in c[i]], -1)
    return q * np.where(q[..., :1] < 0, -1.0, 1.0)


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices `[v]x` `(..., 3, 3)`."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)


def exp_so3(v: np.ndarray) -> np.ndarray:
    """The exponential map: rotation matrices of rotation vectors `(..., 3)` (Rodrigues)."""
    v = np.asarray(v, dtype=float)
    a = np.linalg.norm(v, axis=-1)[..., None, None]
    small = a < 1e-8
    a_safe = np.where(small, 1.0, a)
    s = np.where(small, 1 - a**2 / 6, np.sin(a_safe) / a_safe)
    c = np.where(small, 0.5 - a**2 / 24, (1 - np.cos(a_safe)) / a_safe**2)
    K = skew(v)
    return np.eye(3) + s * K + c * (K @ K)


def log_so3(R: np.ndarray) -> np.ndarray:
    """The logarithm map: rotation vectors `(..., 3)` of rotation matrices (angles < pi),
    through the quaternion (accurate for small and large angles alike)."""
    q = matrix_to_quat(R)
    vn = np.linalg.norm(q[..., 1:], axis=-1)
    angle = 2 * np.arctan2(vn, q[..., 0])
    scale = np.where(vn < 1e-12, 2.0 / np.maximum(q[..., 0], 1e-300), angle / np.maximum(vn, 1e-300))
    return q[..., 1:] * scale[..., None]


def continuous_sign(q: np.ndarray, valid: np.ndarray | None = None) -> np.ndarray:
    """Quaternions `(n, 4)` with their signs chosen so that each valid sample has a positive
    dot product with the previous valid one (q and -q are one attitude): a sign that flips
    between samples is handled, not refused."""
    q = np.array(q, dtype=float)
    valid = np.all(np.isfinite(q), axis=1) if valid is None else valid
    idx = np.flatnonzero(valid)
    if idx.size < 2:
        return q
    d = np.einsum("ij,ij->i", q[idx[1:]], q[idx[:-1]])
    flips = np.concatenate([[0], np.cumsum(d < 0)]) % 2
    q[idx] *= np.where(flips == 1, -1.0, 1.0)[:, None]
    return q


def fill_gaps(q: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Quaternions `(n, 4)` (continuous in sign) with the samples that are not `valid`
    interpolated component-wise between their valid neighbours and renormalised (the
    smoother's starting nominal; its measurements there are masked)."""
    t = np.arange(len(q))
    idx = np.flatnonzero(valid)
    out = np.stack([np.interp(t, idx, q[idx, i]) for i in range(4)], -1)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def euler_321(R: np.ndarray) -> np.ndarray:
    """3-2-1 Euler angles `(..., 3)` `[phi, theta, psi]` of body -> Earth matrices. Along a
    time axis (the first of `(N, 3, 3)`) they stay on a branch continuous in time: `phi` and
    `psi` unwrapped, and through `theta = +-90 deg` the branch `(phi + pi, pi - theta,
    psi + pi)` (the same attitude) is taken where it is the continuous one."""
    R = np.asarray(R, dtype=float)
    phi = np.arctan2(R[..., 2, 1], R[..., 2, 2])
    theta = -np.arcsin(np.clip(R[..., 2, 0], -1.0, 1.0))
    psi = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    e = np.stack([phi, theta, psi], -1)
    if R.ndim != 3 or len(R) < 2:
        return e
    wrap = lambda x: (x + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
    # crossing theta = +-90 deg, the principal phi and psi both jump by ~pi: switch branch
    jump = (np.abs(wrap(np.diff(phi))) > np.pi / 2) & (np.abs(wrap(np.diff(psi))) > np.pi / 2)
    alt = np.concatenate([[0], np.cumsum(jump)]) % 2 == 1
    e = np.where(alt[:, None], np.stack([phi + np.pi, np.pi - theta, psi + np.pi], -1), e)
    return np.unwrap(e, axis=0)


def euler_to_matrix(phi, theta, psi) -> np.ndarray:
    """Body -> Earth matrices of 3-2-1 Euler angles: `Rz(psi) Ry(theta) Rx(phi)`."""
    phi, theta, psi = (np.asarray(a, dtype=float) for a in (phi, theta, psi))
    cf, sf, ct, st, cp, sp = (np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta),
                              np.cos(psi), np.sin(psi))
    return np.stack([
        np.stack([ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp], -1),
        np.stack([ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp], -1),
        np.stack([-st, sf * ct, cf * ct], -1),
    ], -2)


def axis_rotation(axis: str, angle) -> np.ndarray:
    """Matrices `(..., 3, 3)` of right-handed rotations by `angle` (rad) about body axis
    `axis` (`"X"`, `"Y"` or `"Z"`)."""
    a = np.asarray(angle, dtype=float)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    rows = {"X": [[o, z, z], [z, c, -s], [z, s, c]],
            "Y": [[c, z, s], [z, o, z], [-s, z, c]],
            "Z": [[c, -s, z], [s, c, z], [z, z, o]]}[axis.upper()]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def euler_to_matrix_ordered(angles: np.ndarray, order: str) -> np.ndarray:
    """Body -> Earth matrices of Euler angles `(..., 3)` (rad) about the body's x, y and z
    axes (roll, pitch, yaw), applied as intrinsic rotations in `order`: `"ZYX"` is
    `Rz(yaw) Ry(pitch) Rx(roll)` (3-2-1, [`euler_to_matrix`][]), `"XYZ"` is
    `Rx(roll) Ry(pitch) Rz(yaw)`, and so on for the six orders of three distinct axes."""
    order = order.upper()
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"Euler order {order!r}: three distinct axes of X, Y, Z expected")
    angles = np.asarray(angles, dtype=float)
    R = None
    for ax in order:
        Ri = axis_rotation(ax, angles[..., "XYZ".index(ax)])
        R = Ri if R is None else R @ Ri
    return R


def to_ned(pos: np.ndarray, R: np.ndarray, frame: str) -> tuple[np.ndarray, np.ndarray]:
    """Positions `(n, 3)` and body -> world matrices `(n, 3, 3)` of a tracking `frame`
    (`FRAMES`) in north-east-down, world and body axes alike: `x_ned = C x`,
    `R_ned = C R C^T`."""
    C = FRAMES[frame]
    return pos @ C.T, C @ R @ C.T
