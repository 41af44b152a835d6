"""fwid.simulate against independent integrators, and the Experiment plumbing."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fwid  # noqa: F401  (float64)
from fwid.models import longitudinal
from fwid.simulation import (
    Experiment,
    input_at,
    simulate,
    simulate_forces,
    stack_experiments,
    unstack_experiments,
)

CONSTS = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
BIASES = dict(bq=0.02, bu=-0.01, bw=0.015, btheta=-0.005)
X0 = np.array([0.1, -0.05, 0.02, 0.03])


def lon_matrices(p, c):
    """Eq. (7) written out by hand: x' = A x + B [de, 1]."""
    m, Iy, g, u0, w0, th0 = (c[k] for k in ("mass", "Iy", "g", "u0", "w0", "theta0"))
    A = np.array([
        [p["Mq"] / Iy, p["Mu"] / Iy, p["Mw"] / Iy, 0.0],
        [p["Xq"] / m - w0, p["Xu"] / m, p["Xw"] / m, -g * np.cos(th0)],
        [p["Zq"] / m + u0, p["Zu"] / m, p["Zw"] / m, -g * np.sin(th0)],
        [1.0, 0.0, 0.0, 0.0],
    ])
    B = np.array([
        [p["Mde"] / Iy, p["bq"]],
        [p["Xde"] / m, p["bu"]],
        [p["Zde"] / m, p["bw"]],
        [0.0, p["btheta"]],
    ])
    return A, B


def numpy_rk4(A, B, t, u, x0):
    """Classical RK4 at the sample times, the input linear between samples."""
    x = np.array(x0, dtype=float)
    out = [x.copy()]
    for k in range(len(t) - 1):
        h = t[k + 1] - t[k]
        ua = np.array([u[k], 1.0])
        um = np.array([0.5 * (u[k] + u[k + 1]), 1.0])
        ub = np.array([u[k + 1], 1.0])
        k1 = A @ x + B @ ua
        k2 = A @ (x + 0.5 * h * k1) + B @ um
        k3 = A @ (x + 0.5 * h * k2) + B @ um
        k4 = A @ (x + h * k3) + B @ ub
        x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x.copy())
    return np.array(out)


def smooth_input(t):
    return 0.04 * np.sin(2 * np.pi * 1.1 * t) * np.exp(-0.2 * t)


@pytest.fixture(scope="module")
def model():
    return longitudinal().with_params(BIASES)


@pytest.fixture(scope="module")
def ab(model):
    p = {k: float(v) for k, v in model.params.items()}
    return lon_matrices(p, CONSTS)


def _sim(model, dt, T=4.5, u_fn=smooth_input):
    n = int(round(T / dt)) + 1
    t = np.arange(n) * dt
    u = u_fn(t)
    exp = Experiment(t, u, np.zeros((n, 4)), X0, CONSTS)
    xs, ys = simulate(model, exp)
    return t, u, np.asarray(xs), np.asarray(ys)


def test_matches_numpy_rk4_loop(model, ab):
    t, u, xs, ys = _sim(model, 0.005)
    ref = numpy_rk4(*ab, t, u, X0)
    assert xs.shape == ref.shape == (901, 4)
    np.testing.assert_array_equal(xs[0], X0)
    np.testing.assert_allclose(xs, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    # outputs are the states for the DelFly models
    np.testing.assert_array_equal(ys, xs)


def _scipy_reference(ab, t, u):
    A, B = ab

    def rhs(tau, x):
        return A @ x + B @ np.array([np.interp(tau, t, u), 1.0])

    sol = solve_ivp(rhs, (t[0], t[-1]), X0, method="DOP853", t_eval=t, rtol=1e-12,
                    atol=1e-14, max_step=t[1] - t[0])
    assert sol.success
    return sol.y.T


def test_matches_scipy_to_rk4_truncation_and_is_fourth_order(model, ab):
    t, u, xs, _ = _sim(model, 0.005)
    ref = _scipy_reference(ab, t, u)
    scale = np.abs(ref).max()
    err = np.abs(xs - ref).max() / scale
    # RK4 truncation level at 200 Hz for this model (fastest pole about -17 1/s)
    assert 1e-10 < err < 1e-5, err
    # the same scheme at half the step (numpy loop, checked equal to fwid above) is about
    # 2^4 times closer: fwid's integrator is fourth order, not merely convergent
    t2 = np.arange(2 * (len(t) - 1) + 1) * 0.0025
    u2 = smooth_input(t2)
    half = numpy_rk4(*ab, t2, u2, X0)[::2]
    ref2 = _scipy_reference(ab, t2, u2)[::2]
    err2 = np.abs(half - ref2).max() / scale
    assert 10.0 < err / err2 < 24.0, (err, err2)


def test_input_at_exact_on_linear_ramp():
    t0, dt, n = 0.3, 0.01, 50
    t = t0 + dt * np.arange(n)
    u = np.stack([1.5 - 2.0 * t, 0.25 + 7.0 * t], axis=-1)
    rng = np.random.default_rng(0)
    taus = np.concatenate([t, t[:-1] + 0.5 * dt, rng.uniform(t[0], t[-1], 40)])
    got = jax.vmap(lambda tau: input_at(tau, t0, dt, jnp.asarray(u)))(jnp.asarray(taus))
    expected = np.stack([1.5 - 2.0 * taus, 0.25 + 7.0 * taus], axis=-1)
    np.testing.assert_allclose(np.asarray(got), expected, rtol=0, atol=1e-13)


def test_input_at_interpolates_between_samples():
    u = jnp.array([[0.0], [1.0], [0.0], [4.0]])
    f = lambda tau: float(input_at(tau, 0.0, 0.5, u)[0])  # noqa: E731
    assert f(0.25) == pytest.approx(0.5)
    assert f(0.5) == pytest.approx(1.0)
    assert f(0.875) == pytest.approx(0.25)
    assert f(1.25) == pytest.approx(2.0)
    assert f(1.5) == pytest.approx(4.0)


def test_simulate_forces_along_trajectory(model):
    t, u, xs, _ = _sim(model, 0.005)
    exp = Experiment(t, u, xs, X0, CONSTS)
    F = np.asarray(simulate_forces(model, jnp.asarray(xs), exp))
    p = {k: float(v) for k, v in model.params.items()}
    q, uu, w = xs[:, 0], xs[:, 1], xs[:, 2]
    for j, ax in enumerate("XZM"):
        ref = p[ax + "q"] * q + p[ax + "u"] * uu + p[ax + "w"] * w + p[ax + "de"] * u
        np.testing.assert_allclose(F[:, j], ref, rtol=1e-12, atol=1e-15)


def _exp(n, seed, dt=0.01, t0=0.0):
    rng = np.random.default_rng(seed)
    t = t0 + dt * np.arange(n)
    return Experiment(t, rng.standard_normal((n, 1)), rng.standard_normal((n, 4)),
                      rng.standard_normal(4), dict(CONSTS, mass=0.02 + 0.001 * seed),
                      forces=rng.standard_normal((n, 3)))


def test_stack_unstack_round_trip():
    exps = [_exp(30, 1), _exp(45, 2, t0=2.0), _exp(12, 3)]
    batch = stack_experiments(exps)
    assert batch.t.shape == (3, 45)
    assert batch.u.shape == (3, 45, 1)
    assert batch.z.shape == (3, 45, 4)
    assert batch.x0.shape == (3, 4)
    assert batch.forces.shape == (3, 45, 3)
    assert batch.consts["mass"].shape == (3,)
    back = unstack_experiments(batch)
    assert len(back) == 3
    for a, b in zip(exps, back):
        assert b.n == a.n
        for field in ("t", "u", "z", "x0", "mask", "forces"):
            np.testing.assert_array_equal(np.asarray(getattr(b, field)),
                                          np.asarray(getattr(a, field)), err_msg=field)
        assert set(b.consts) == set(a.consts)
        for k in a.consts:
            assert float(b.consts[k]) == float(a.consts[k])


def test_padding_gets_mask_zero_and_holds():
    exps = [_exp(30, 1), _exp(45, 2, t0=2.0)]
    batch = stack_experiments(exps, n=50)
    mask = np.asarray(batch.mask)
    assert mask.shape == (2, 50)
    np.testing.assert_array_equal(mask[0], np.r_[np.ones(30), np.zeros(20)])
    np.testing.assert_array_equal(mask[1], np.r_[np.ones(45), np.zeros(5)])
    t = np.asarray(batch.t)
    # time continues on the same uniform grid; inputs hold their last value
    np.testing.assert_allclose(np.diff(t[0]), 0.01, rtol=1e-9)
    np.testing.assert_allclose(np.diff(t[1]), 0.01, rtol=1e-9)
    u = np.asarray(batch.u)
    np.testing.assert_array_equal(u[0, 30:], np.repeat(u[0, 29:30], 20, axis=0))
    # without forces on every experiment, the batch has none
    no_f = Experiment(np.arange(10) * 0.01, np.zeros(10), np.zeros((10, 4)))
    assert stack_experiments([exps[0], no_f]).forces is None


def test_simulate_on_padded_batch_matches_unpadded(model, ab):
    n = 901
    t = np.arange(n) * 0.005
    e1 = Experiment(t, smooth_input(t), np.zeros((n, 4)), X0, CONSTS)
    k = 600
    u2 = smooth_input(t[:k] + 0.7)
    e2 = Experiment(t[:k], u2, np.zeros((k, 4)), -X0, CONSTS)
    batch = stack_experiments([e1, e2])
    ys = np.asarray(jax.vmap(lambda e: simulate(model, e)[1])(batch))
    assert ys.shape == (2, n, 4)
    np.testing.assert_allclose(ys[0], np.asarray(simulate(model, e1)[1]), rtol=0, atol=1e-14)
    ref2 = numpy_rk4(*ab, t[:k], u2, -X0)
    np.testing.assert_allclose(ys[1, :k], ref2, rtol=0, atol=1e-12 * np.abs(ref2).max())


def test_sensitivities_equal_jacfwd_of_simulate():
    """One RK4 solve of the state and its sensitivity equations gives jax.jacfwd of the
    RK4 simulation (Runge-Kutta commutes with differentiation), with or without an output
    equation."""
    from fwid.simulation._simulate import simulate_sensitivities

    base = longitudinal(BIASES)

    def h(x, u, p, c):
        return jnp.stack([p["Mq"] * x[0] + u[0], x[1] ** 2, jnp.sin(x[3])])

    with_h = fwid.GreyBoxModel(
        base.f, states=base.states, inputs=base.inputs,
        params={k: base.params[k] for k in base.param_names}, h=h, outputs=("a", "b", "c"),
        constants=base.constants)
    t = np.arange(300) * 0.005
    u = 0.1 * np.sin(3 * t)[:, None]
    for m in (base, with_h):
        e = Experiment(t, u, np.zeros((t.size, len(m.outputs))), X0, CONSTS)
        th = m.theta()
        ys, dys = simulate_sensitivities(m, e, m.merge, th)
        y_ref = simulate(m, e, m.merge(th))[1]
        J = jax.jacfwd(lambda th_, m=m, e=e: simulate(m, e, m.merge(th_))[1])(th)
        assert dys.shape == (t.size, len(m.outputs), th.shape[0])
        np.testing.assert_allclose(ys, y_ref, rtol=0, atol=1e-14)
        np.testing.assert_allclose(dys, J, rtol=0, atol=1e-12 * float(jnp.max(jnp.abs(J))))


def test_reverse_mode_equals_forward_mode(model):
    """The solve is a `lax.scan` of the solver's steps, so reverse-mode autodiff (what a
    user's `jax.grad` of a cost runs) gives the forward-mode gradient."""
    t = np.arange(400) * 0.005
    e = Experiment(t, smooth_input(t), np.zeros((t.size, 4)), X0, CONSTS)
    th = model.theta()

    def cost(th_):
        return jnp.sum(simulate(model, e, model.merge(th_))[1] ** 2)

    g_rev = jax.grad(cost)(th)
    g_fwd = jax.jacfwd(cost)(th)
    assert float(jnp.max(jnp.abs(g_fwd))) > 0
    np.testing.assert_allclose(g_rev, g_fwd, rtol=1e-10, atol=1e-12 * float(jnp.max(jnp.abs(g_fwd))))
