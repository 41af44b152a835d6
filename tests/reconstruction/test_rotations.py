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


def test_euler_orders_against_axis_products():
    """Each of the six intrinsic orders is the product of single-axis rotations in that
    order; ZYX is the 3-2-1 convention of euler_to_matrix."""
    from fwid.reconstruction._rotations import (
        axis_rotation, euler_to_matrix, euler_to_matrix_ordered)

    rng = np.random.default_rng(3)
    a = rng.uniform(-1.2, 1.2, (7, 3))
    np.testing.assert_allclose(euler_to_matrix_ordered(a, "zyx"),
                               euler_to_matrix(a[:, 0], a[:, 1], a[:, 2]), atol=1e-14)
    for order in ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"):
        R = euler_to_matrix_ordered(a, order)
        ref = np.eye(3)
        for ax in order:
            ref = ref @ axis_rotation(ax, a[:, "XYZ".index(ax)])
        np.testing.assert_allclose(R, ref, atol=1e-14)
        np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape),
                                   atol=1e-13)
    # a rotation about z alone turns x into y (right-handed)
    np.testing.assert_allclose(axis_rotation("Z", np.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_euler_orders_round_trip_against_scipy():
    """Each order, angles given as roll, pitch, yaw, is scipy's upper-case (intrinsic)
    `Rotation.from_euler` with the angles in that order; and back through `as_euler`."""
    from scipy.spatial.transform import Rotation

    from fwid.reconstruction._rotations import euler_to_matrix_ordered

    rng = np.random.default_rng(5)
    rpy = rng.uniform(-1.2, 1.2, (9, 3))
    for order in ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"):
        pick = ["XYZ".index(ax) for ax in order]
        R = euler_to_matrix_ordered(rpy, order)
        np.testing.assert_allclose(R, Rotation.from_euler(order, rpy[:, pick]).as_matrix(),
                                   atol=1e-13, err_msg=order)
        back = np.empty_like(rpy)
        back[:, pick] = Rotation.from_matrix(R).as_euler(order)
        np.testing.assert_allclose(back, rpy, atol=1e-10, err_msg=order)
