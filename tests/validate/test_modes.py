"""Eigenvalues and modes of a known linear model."""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.models import GreyBoxModel
from fwid.validate import eigenvalues, modes

WN, ZETA, POLE = 5.0, 0.3, -2.0


def _model():
    """x' = A x with a 2x2 block (wn = 5, zeta = 0.3) and a real pole at -2."""

    def f(x, u, p, c):
        a, b, r = x
        return jnp.stack([b, -p["wn"] ** 2 * a - 2 * p["zeta"] * p["wn"] * b + u[0],
                          p["pole"] * r + c["k"] * u[0]])

    return GreyBoxModel(f, states=("a", "b", "r"), inputs=("u",),
                        params=dict(wn=WN, zeta=ZETA, pole=POLE), constants=("k",))


def test_eigenvalues_of_known_A():
    ev = eigenvalues(_model(), dict(k=jnp.asarray(1.0)))
    wd = WN * np.sqrt(1 - ZETA**2)
    expected = np.array([-ZETA * WN + 1j * wd, POLE, -ZETA * WN - 1j * wd])
    assert ev.shape == (3,)
    # sorted by imaginary part (descending) then real part
    np.testing.assert_allclose(ev, expected, rtol=1e-12, atol=1e-12)


def test_modes_give_wn_zeta_tau():
    ms = modes(eigenvalues(_model(), dict(k=jnp.asarray(1.0))))
    osc = [m for m in ms if m["kind"] == "oscillatory"]
    aper = [m for m in ms if m["kind"] == "aperiodic"]
    assert len(osc) == 1 and len(aper) == 1
    o, a = osc[0], aper[0]
    wd = WN * np.sqrt(1 - ZETA**2)
    assert o["wn"] == pytest.approx(WN, rel=1e-12)
    assert o["zeta"] == pytest.approx(ZETA, rel=1e-12)
    assert o["freq_hz"] == pytest.approx(wd / (2 * np.pi), rel=1e-12)
    assert o["period"] == pytest.approx(2 * np.pi / wd, rel=1e-12)
    assert o["stable"] is True
    assert a["tau"] == pytest.approx(0.5, rel=1e-12)
    assert a["stable"] is True and a["t_double"] is None


def test_unstable_and_params_override():
    m = _model()
    ev = eigenvalues(m, dict(k=jnp.asarray(1.0)), params=dict(m.params, pole=jnp.asarray(0.5),
                                                             zeta=jnp.asarray(-0.1)))
    ms = modes(ev)
    osc = next(x for x in ms if x["kind"] == "oscillatory")
    aper = next(x for x in ms if x["kind"] == "aperiodic")
    assert osc["zeta"] == pytest.approx(-0.1, rel=1e-12) and osc["stable"] is False
    assert aper["stable"] is False
    assert aper["t_double"] == pytest.approx(np.log(2) / 0.5, rel=1e-12)


def test_modes_of_plain_eigenvalues():
    ms = modes([-1.0 + 2.0j, -1.0 - 2.0j, -4.0, -0.5 + 0.1j, -0.5 - 0.1j])
    kinds = sorted(m["kind"] for m in ms)
    assert kinds == ["aperiodic", "oscillatory", "oscillatory"]
    wns = sorted(m["wn"] for m in ms if m["kind"] == "oscillatory")
    np.testing.assert_allclose(wns, [np.hypot(0.5, 0.1), np.sqrt(5.0)], rtol=1e-12)


def test_modes_name_natural_and_damped_frequency():
    osc = [m for m in modes(eigenvalues(_model(), dict(k=jnp.asarray(1.0))))
           if m["kind"] == "oscillatory"][0]
    wd = WN * np.sqrt(1 - ZETA**2)
    assert osc["natural_freq_hz"] == pytest.approx(WN / (2 * np.pi), rel=1e-10)
    assert osc["damped_freq_hz"] == pytest.approx(wd / (2 * np.pi), rel=1e-10)
    assert osc["freq_hz"] == osc["damped_freq_hz"]  # the old key stays


def _pendulum_in_airspeed():
    """A model in absolute states: x = (V, a); A depends on V, and is singular at V = 0."""

    def f(x, u, p, c):
        V, a = x
        return jnp.stack([-p["d"] * V + u[0], -p["k"] * V**2 * a])

    return GreyBoxModel(f, states=("V", "a"), inputs=("T",), params=dict(d=0.5, k=2.0))


def test_state_matrices_and_eigenvalues_at_a_given_point():
    m = _pendulum_in_airspeed()
    A0, B0 = m.state_matrices(m.params, {})  # default: x = 0, u = 0
    assert np.allclose(A0, [[-0.5, 0.0], [0.0, 0.0]])
    A, B = m.state_matrices(m.params, {}, x0=jnp.array([3.0, 0.1]), u0=jnp.array([1.5]))
    assert np.allclose(A, [[-0.5, 0.0], [-2 * 2.0 * 3.0 * 0.1, -2.0 * 9.0]])
    assert np.allclose(B, [[1.0], [0.0]])
    ev = eigenvalues(m, {}, x0=[3.0, 0.1], u0=[1.5])
    assert np.allclose(np.sort(ev.real), [-18.0, -0.5])
    assert np.allclose(np.sort(eigenvalues(m, {}).real), [-0.5, 0.0])  # the default as before
    with pytest.raises(ValueError, match=r"x0 \(3,\).*states V, a"):
        m.state_matrices(m.params, {}, x0=jnp.zeros(3))
