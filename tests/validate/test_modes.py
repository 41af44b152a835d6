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
