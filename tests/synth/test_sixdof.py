"""The nonlinear 6-DOF DelFly agrees with the linearised one (paper Eqs. 7-9) for small
motions, departs from it as the motion grows, and its attitude helpers match scipy's."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fwid.synth import STATES, simulate_flight
from fwid.synth._sixdof import euler_to_quat, initial_state, integrate, quat_to_euler, quat_to_matrix, sixdof_model

LON = ("q", "u", "w", "theta")
LAT = ("p", "r", "v", "phi", "psi")


def _pair(axis, amplitude, flapping, duration=5.0):
    """The linear flight (RK4, 10 substeps, noise-free, exact loads) and the 6-DOF flight
    on the same inputs, flapping frequency and initial state."""
    fl = simulate_flight(axis=axis, input="doublet", amplitude=amplitude, noise=0.0,
                         flapping=flapping, ripple=False, substeps=10, duration=duration,
                         loads="true", seed=3)
    m = fl["meta"]
    model = sixdof_model(m["flap"], fl["t"], m["u_cmd"])
    if not flapping:
        model = eqx.tree_at(lambda s: s.fourier, model, jnp.zeros((3, 2, 6)))
    out = integrate(model, initial_state(m["states"][0]), fl["t"], step=1e-3)
    return fl, out


def _rel(fl, out, names):
    return {s: float(np.sqrt(np.mean((out[s] - fl[s]) ** 2)) / np.ptp(fl[s])) for s in names}


@pytest.mark.parametrize("axis,amp,own,other", [("lon", 0.005, LON, LAT), ("lat", 0.01, LAT, LON)])
def test_small_doublet_agrees_with_the_linear_model(axis, amp, own, other):
    fl, out = _pair(axis, amp, flapping=False)
    rel = _rel(fl, out, own)
    assert max(rel.values()) < 2e-3, rel  # measured ~1e-4 (lon), ~4e-4 (lat)
    if axis == "lon":  # by symmetry an elevator input leaves the lateral states at rest
        for s in other:
            assert np.max(np.abs(out[s] - fl[s])) < 1e-9, s
    loads = ("X", "Z", "M") if axis == "lon" else ("Y", "L", "N")
    rel_loads = _rel(fl, out, loads)
    assert max(rel_loads.values()) < 2e-3, rel_loads


def test_departure_from_the_linear_model_grows_with_the_motion():
    """The longitudinal difference is second order: 20 times the input, ~20 times the
    relative error; the lateral one is third order (the lateral response is odd in the
    rudder by symmetry): ~400 times. A linear model in disguise would stay at round-off."""
    small = _rel(*_pair("lon", 0.005, flapping=False), LON)
    large = _rel(*_pair("lon", 0.1, flapping=False), LON)
    for s in small:
        assert 8 < large[s] / small[s] < 40, (s, small[s], large[s])
    small = _rel(*_pair("lat", 0.005, flapping=False), LAT[:4])
    large = _rel(*_pair("lat", 0.1, flapping=False), LAT[:4])
    for s in small:
        assert 150 < large[s] / small[s] < 800, (s, small[s], large[s])
    assert max(large.values()) > 5e-3


def test_with_flapping_the_longitudinal_response_agrees():
    """With the flapping loads the flapping oscillation's products rectify into small
    cycle-averaged shifts (physics the linear model leaves out); the longitudinal rates and
    velocities and the loads still agree closely."""
    fl, out = _pair("lon", 0.01, flapping=True)
    rel = _rel(fl, out, ("q", "u", "w"))
    assert max(rel.values()) < 0.02, rel
    rel_loads = _rel(fl, out, ("X", "Z", "M"))
    assert max(rel_loads.values()) < 2e-3, rel_loads


def test_attitude_helpers_match_scipy():
    rng = np.random.default_rng(0)
    phi, theta, psi = rng.uniform(-1.4, 1.4, (3, 50))
    q = np.asarray(euler_to_quat(phi, theta, psi))
    ref = Rotation.from_euler("ZYX", np.column_stack([psi, theta, phi]))
    np.testing.assert_allclose(np.asarray(quat_to_matrix(q)), ref.as_matrix(), atol=1e-12)
    sc = ref.as_quat()  # x y z w
    dot = np.abs(np.sum(q * np.column_stack([sc[:, 3], sc[:, :3]]), axis=1))
    np.testing.assert_allclose(dot, 1.0, atol=1e-12)
    phi2, theta2, psi2 = quat_to_euler(q)  # (unwrapped: compare modulo 2 pi)
    np.testing.assert_allclose(theta2, theta, atol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (phi2 - phi))), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (psi2 - psi))), 0.0, atol=1e-12)


def test_initial_state_is_trim_plus_perturbation():
    x0 = np.zeros(9)
    x0[STATES.index("theta")] = 0.1
    x0[STATES.index("u")] = 0.05
    y0 = initial_state(x0)
    assert y0[3] == pytest.approx(0.665484982 + 0.05, abs=1e-8)
    _, theta, _ = quat_to_euler(y0[None, 6:10])
    assert theta[0] == pytest.approx(1.267112137 + 0.1, abs=1e-8)
