"""Rotations against scipy: quaternions, matrices, Euler angles, the exponential map, sign
continuity and the tracking frames."""

import numpy as np
from scipy.spatial.transform import Rotation

from fwid.reconstruction import _rotations as rot


def test_against_scipy():
    r = Rotation.random(50, random_state=1)
    q = r.as_quat()[:, [3, 0, 1, 2]]
    assert np.allclose(rot.quat_to_matrix(q), r.as_matrix(), atol=1e-12)
    back = rot.matrix_to_quat(r.as_matrix())
    assert np.allclose(np.abs(np.sum(back * q, 1)), 1, atol=1e-12)
    v = r.as_rotvec()
    assert np.allclose(rot.exp_so3(v), r.as_matrix(), atol=1e-12)
    assert np.allclose(rot.log_so3(r.as_matrix()), v, atol=1e-9)
    e = rot.euler_321(r.as_matrix()[None])[0]  # no unwrapping along a batch of one
    assert np.allclose(e[:, ::-1], r.as_euler("ZYX"), atol=1e-9)


def test_continuous_sign_and_frames():
    rng = np.random.default_rng(0)
    r = Rotation.from_rotvec(np.linspace(0, 3, 40)[:, None] * [0.2, 0.5, 0.8])
    q = r.as_quat()[:, [3, 0, 1, 2]]
    flipped = q * rng.choice([-1.0, 1.0], (40, 1))
    c = rot.continuous_sign(flipped)
    assert np.all(np.sum(c[1:] * c[:-1], 1) > 0)
    assert np.allclose(np.abs(np.sum(c * q, 1)), 1)
    # y-up: X north, Y up, Z east -> x = X, y = Z, z = -Y, body axes alike
    p, R = rot.to_ned(np.array([[1.0, 2.0, 3.0]]), np.eye(3)[None], "y-up")
    assert np.allclose(p, [[1.0, 3.0, -2.0]]) and np.allclose(R, np.eye(3))
    p, _ = rot.to_ned(np.array([[1.0, 2.0, 3.0]]), np.eye(3)[None], "z-up")
    assert np.allclose(p, [[1.0, -2.0, -3.0]])
