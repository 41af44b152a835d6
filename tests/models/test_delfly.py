"""The DelFly grey-box models against Eqs. (7)-(9) written out by hand, and GreyBoxModel."""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.estimate import least_squares_start
from fwid.models import TABLE1, TABLE4, GreyBoxModel, heading_rate, lateral, longitudinal
from fwid.simulation import Experiment, simulate

LON_C = dict(mass=0.0187, Iy=7.3e-5, g=9.81, u0=0.41, w0=0.83, theta0=1.31)
LAT_C = dict(mass=0.0187, Ix=8.1e-5, Iz=2.7e-5, Ixz=3.3e-6, g=9.81, u0=0.41, w0=0.83,
             theta0=1.31)


def _random_params(names, seed):
    rng = np.random.default_rng(seed)
    return {k: float(v) for k, v in zip(names, rng.uniform(-1, 1, len(names)) * 1e-2)}


def _eval(model, x, u, c):
    return np.asarray(model.f(jnp.asarray(x), jnp.asarray(u), model.params,
                              {k: jnp.asarray(v) for k, v in c.items()}))


# -- Eq. (7) -----------------------------------------------------------------------------
def eq7(p, c):
    m, Iy, g, u0, w0, th = (c[k] for k in ("mass", "Iy", "g", "u0", "w0", "theta0"))
    A = np.array([
        [p["Mq"] / Iy, p["Mu"] / Iy, p["Mw"] / Iy, 0.0],
        [p["Xq"] / m - w0, p["Xu"] / m, p["Xw"] / m, -g * np.cos(th)],
        [p["Zq"] / m + u0, p["Zu"] / m, p["Zw"] / m, -g * np.sin(th)],
        [1.0, 0.0, 0.0, 0.0],
    ])
    B = np.array([[p["Mde"] / Iy], [p["Xde"] / m], [p["Zde"] / m], [0.0]])
    bias = np.array([p["bq"], p["bu"], p["bw"], p["btheta"]])
    return A, B, bias


def test_longitudinal_matches_eq7():
    p = _random_params(longitudinal().params, 1)
    model = longitudinal(p)
    A, B = model.state_matrices(model.params, LON_C)
    A_ref, B_ref, bias = eq7(p, LON_C)
    np.testing.assert_allclose(np.asarray(A), A_ref, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(np.asarray(B), B_ref, rtol=1e-13, atol=1e-15)
    # the model is affine: f(x, u) = A x + B u + b, with the bias terms as the unit input
    rng = np.random.default_rng(2)
    for _ in range(3):
        x, u = rng.standard_normal(4), rng.standard_normal(1)
        np.testing.assert_allclose(_eval(model, x, u, LON_C), A_ref @ x + B_ref @ u + bias,
                                   rtol=1e-12, atol=1e-14)


def test_longitudinal_metadata():
    m = longitudinal()
    assert m.states == m.outputs == ("q", "u", "w", "theta")
    assert m.inputs == ("de",)
    assert m.free == tuple(TABLE1) + ("bq", "bu", "bw", "btheta")
    assert m.local == ("bq", "bu", "bw", "btheta")
    assert set(m.constants) == {"mass", "Iy", "g", "u0", "w0", "theta0"}
    assert m.force_names == ("X", "Z", "M")
    assert m.outputs_are_states
    for k, v in TABLE1.items():
        assert float(m.params[k]) == v
    assert longitudinal(biases=False).free == tuple(TABLE1)
    assert float(longitudinal(dict(Mq=-2e-3)).params["Mq"]) == -2e-3


def test_longitudinal_forces_are_eqs_1_3_5_perturbations():
    p = _random_params(longitudinal().params, 3)
    model = longitudinal(p)
    x, u = np.array([0.3, -0.2, 0.1, 0.05]), np.array([0.07])
    F = np.asarray(model.forces(jnp.asarray(x), jnp.asarray(u), model.params, LON_C))
    q, uu, w, _ = x
    for j, ax in enumerate("XZM"):
        ref = p[ax + "q"] * q + p[ax + "u"] * uu + p[ax + "w"] * w + p[ax + "de"] * u[0]
        assert F[j] == pytest.approx(ref, rel=1e-13)


# -- Eq. (8) -----------------------------------------------------------------------------
def eq8(p, c):
    m, Ix, Iz, Ixz, g, u0, w0, th = (
        c[k] for k in ("mass", "Ix", "Iz", "Ixz", "g", "u0", "w0", "theta0"))
    Ic = Ix * Iz - Ixz**2

    def row_pr(a, b, s):  # a/Ic L_s + b/Ic N_s
        return a / Ic * p["L" + s] + b / Ic * p["N" + s]

    A = np.array([
        [row_pr(Iz, Ixz, "p"), row_pr(Iz, Ixz, "r"), row_pr(Iz, Ixz, "v"), 0.0],
        [row_pr(Ixz, Ix, "p"), row_pr(Ixz, Ix, "r"), row_pr(Ixz, Ix, "v"), 0.0],
        [p["Yp"] / m + w0, p["Yr"] / m - u0, p["Yv"] / m, g * np.cos(th)],
        [1.0, np.tan(th), 0.0, 0.0],
    ])
    B = np.array([[row_pr(Iz, Ixz, "dr")], [row_pr(Ixz, Ix, "dr")], [p["Ydr"] / m], [0.0]])
    bias = np.array([p["bp"], p["br"], p["bv"], p["bphi"]])
    return A, B, bias


def test_lateral_matches_eq8():
    p = _random_params(lateral().params, 4)
    model = lateral(p)
    A, B = model.state_matrices(model.params, LAT_C)
    A_ref, B_ref, bias = eq8(p, LAT_C)
    np.testing.assert_allclose(np.asarray(A), A_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.asarray(B), B_ref, rtol=1e-12, atol=1e-15)
    rng = np.random.default_rng(5)
    for _ in range(3):
        x, u = rng.standard_normal(4), rng.standard_normal(1)
        np.testing.assert_allclose(_eval(model, x, u, LAT_C), A_ref @ x + B_ref @ u + bias,
                                   rtol=1e-12, atol=1e-14)


def test_lateral_product_of_inertia_couples_roll_and_yaw():
    # with Ixz = 0 the roll row has only L / Ix and the yaw row only N / Iz
    p = _random_params(lateral().params, 6)
    c = dict(LAT_C, Ixz=0.0)
    A, _ = lateral(p).state_matrices(lateral(p).params, c)
    A = np.asarray(A)
    assert A[0, 0] == pytest.approx(p["Lp"] / c["Ix"], rel=1e-13)
    assert A[1, 1] == pytest.approx(p["Nr"] / c["Iz"], rel=1e-13)


def test_lateral_metadata():
    m = lateral()
    assert m.states == ("p", "r", "v", "phi")
    assert m.inputs == ("dr",)
    assert m.free == tuple(TABLE4) + ("bp", "br", "bv", "bphi")
    assert set(m.constants) == {"mass", "Ix", "Iz", "Ixz", "g", "u0", "w0", "theta0"}
    assert m.force_names == ("Y", "L", "N")


def test_heading_rate_eq9():
    assert float(heading_rate(0.2, 1.2)) == pytest.approx(0.2 / np.cos(1.2), rel=1e-14)


# -- GreyBoxModel API -------------------------------------------------------------------
def test_with_params_is_a_copy_and_checks_names():
    m = longitudinal()
    m2 = m.with_params({"Mq": -5e-3}, Xu=0.1)
    assert float(m2.params["Mq"]) == -5e-3 and float(m2.params["Xu"]) == 0.1
    assert float(m.params["Mq"]) == TABLE1["Mq"]  # original untouched
    assert m2.free == m.free
    with pytest.raises(KeyError, match="Mqq"):
        m.with_params(Mqq=1.0)


def test_with_free_theta_merge():
    m = longitudinal(dict(Mq=-4e-3, bq=0.5))
    sub = m.with_free(["bq", "Mq", "Xu"])
    assert sub.free == ("Xu", "Mq", "bq")  # params' order, not the given order
    np.testing.assert_array_equal(np.asarray(sub.theta()), [TABLE1["Xu"], -4e-3, 0.5])
    merged = sub.merge(jnp.array([1.0, 2.0, 3.0]))
    assert float(merged["Xu"]) == 1.0 and float(merged["Mq"]) == 2.0
    assert float(merged["bq"]) == 3.0
    assert float(merged["Zw"]) == TABLE1["Zw"]  # fixed parameters keep their values
    assert set(merged) == set(m.params)
    # merge onto another parameter dict
    other = dict(m.params, Zw=jnp.asarray(9.0))
    assert float(sub.merge(jnp.zeros(3), other)["Zw"]) == 9.0
    # theta/merge round trip
    full = longitudinal()
    assert all(float(full.merge(full.theta())[k]) == float(v) for k, v in full.params.items())
    # metadata survives with_free
    assert sub.constants == m.constants and sub.local == m.local and sub.name == "lon"
    assert sub.outputs_are_states
    assert sub.with_free([]).theta().shape == (0,)
    with pytest.raises(ValueError, match="nope"):
        m.with_free(["Mq", "nope"])


def test_with_params_keeps_parameter_order():
    # JAX rebuilds dicts in sorted-key order, so the declared order lives in `param_names`;
    # `free`, `theta` and the fit's table follow it (Table 1's order).
    m = longitudinal()
    m2 = m.with_params(Mq=-4e-3)
    assert m2.param_names == m.param_names == tuple(m.params)
    assert m2.with_free(m.free).free == m.free
    assert m2.with_free(m.free).param_names == m.param_names


def test_output_names_required_with_h():
    with pytest.raises(ValueError, match="outputs"):
        GreyBoxModel(lambda x, u, p, c: x, states=("a",), inputs=("u",), params=dict(k=1.0),
                     h=lambda x, u, p, c: x)


# -- a user-defined model in a few lines (ATTAS-like short period, Jategaonkar) -----------
def _short_period():
    def f(x, u, p, c):
        alpha, q = x
        return jnp.stack([p["Za"] * alpha + (1.0 + p["Zq"]) * q + p["Zde"] * u[0],
                          p["Ma"] * alpha + p["Mq"] * q + p["Mde"] * u[0]])

    def h(x, u, p, c):  # alpha, q and the normal acceleration (in units of V)
        return jnp.stack([x[0], x[1], p["Za"] * x[0] + p["Zq"] * x[1] + p["Zde"] * u[0]])

    params = dict(Za=-1.4, Zq=-0.02, Zde=-0.15, Ma=-9.0, Mq=-2.1, Mde=-11.0)
    return GreyBoxModel(f, h=h, states=("alpha", "q"), inputs=("de",),
                        outputs=("alpha", "q", "az"), params=params, name="sp"), params


def test_user_defined_model_simulates():
    model, p = _short_period()
    assert not model.outputs_are_states
    A = np.array([[p["Za"], 1 + p["Zq"]], [p["Ma"], p["Mq"]]])
    b = np.array([p["Zde"], p["Mde"]])
    dt, n = 0.04, 100
    t = np.arange(n) * dt
    u = 0.02 * np.sin(1.7 * t) + 0.01 * (t > 1.0)
    x0 = np.array([0.01, -0.02])
    xs, ys = simulate(model, Experiment(t, u, np.zeros((n, 3)), x0))
    # the same classical RK4 in numpy
    x, ref = x0.copy(), [x0.copy()]
    for k in range(n - 1):
        um = 0.5 * (u[k] + u[k + 1])
        k1 = A @ x + b * u[k]
        k2 = A @ (x + 0.5 * dt * k1) + b * um
        k3 = A @ (x + 0.5 * dt * k2) + b * um
        k4 = A @ (x + dt * k3) + b * u[k + 1]
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        ref.append(x.copy())
    ref = np.array(ref)
    np.testing.assert_allclose(np.asarray(xs), ref, rtol=0, atol=1e-13)
    ys = np.asarray(ys)
    assert ys.shape == (n, 3)
    np.testing.assert_allclose(ys[:, :2], ref, rtol=0, atol=1e-13)
    az = p["Za"] * ref[:, 0] + p["Zq"] * ref[:, 1] + p["Zde"] * u
    np.testing.assert_allclose(ys[:, 2], az, rtol=0, atol=1e-13)
    # a model without a force model starts from the state-derivative regression
    model_x = GreyBoxModel(model.f, states=model.states, inputs=model.inputs,
                           params={k: 0.0 for k in p}, name="sp")
    start = least_squares_start(model_x, [Experiment(t, u, np.asarray(xs), x0)])
    th = np.asarray(start.theta())
    # equation error with a numerically differentiated 25 Hz record: roughly right
    np.testing.assert_allclose(th, [p[k] for k in model_x.free], rtol=0.1, atol=0.01)
