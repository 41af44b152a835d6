"""The filter-error method (`fwid.fit(..., method="filter-error")`, Jategaonkar Ch. 5).

The Riccati solution against scipy's, autodiff gradients of the filter-error likelihood
against finite differences, a simulated flight in turbulence (no data files needed), and
FVSysID test cases 4 and 2 (skipped without ../shared/flightdata).
"""

import sys
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

import fwid
from fwid.estimate._filter_error import _innovations
from fwid.estimate._riccati import care, discretise, steady_state_gain

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from cases import tc02  # noqa: E402
from cases import tc04  # noqa: E402
from cases.textbook import fwid_model  # noqa: E402

TRUE = dict(Lp=-4.0, Lr=1.0, Lda=-10.0, Np=-0.5, Nr=-0.8, Ndr=-3.0)
BOOK_FEM = dict(CD0=0.122688, CDa=0.320055, CLa=4.32785, Cma=-0.967854, Cmq=-34.7098,
                Cmde=-1.52913)  # mDefCase04, parFEM


def _f(x, u, p, c):
    return jnp.stack([p["Lp"] * x[0] + p["Lr"] * x[1] + p["Lda"] * u[0],
                      p["Np"] * x[0] + p["Nr"] * x[1] + p["Ndr"] * u[1]])


def _h(x, u, p, c):
    return jnp.stack([x[0], x[1], _f(x, u, p, c)[0]])


def _model(**values):
    return fwid.GreyBoxModel(_f, h=_h, states=("p", "r"), inputs=("da", "dr"),
                             outputs=("p", "r", "pdot"), params={**TRUE, **values},
                             name="rollyaw")


def _turbulent_flight(seed=0, F=(0.2, 0.1)):
    """20 s at 20 Hz with aileron and rudder doublets, process noise F (turbulence) and
    measurement noise; simulated by the exact discretisation of the true linear model."""
    dt, n = 0.05, 401
    t = dt * np.arange(n)
    u = np.zeros((n, 2))
    u[(t > 1) & (t < 2), 0], u[(t >= 2) & (t < 3), 0] = 0.2, -0.2
    u[(t > 8) & (t < 9), 1], u[(t >= 9) & (t < 10), 1] = 0.2, -0.2
    A = np.array([[TRUE["Lp"], TRUE["Lr"]], [TRUE["Np"], TRUE["Nr"]]])
    B = np.array([[TRUE["Lda"], 0.0], [0.0, TRUE["Ndr"]]])
    Phi, Q = (np.asarray(a) for a in discretise(jnp.asarray(A), jnp.diag(jnp.square(
        jnp.asarray(F))), dt))
    Gam = np.linalg.solve(A, (Phi - np.eye(2))) @ B
    rng = np.random.default_rng(seed)
    Lq = np.linalg.cholesky(Q)
    x, xs = np.zeros(2), []
    for k in range(n):
        xs.append(x)
        x = Phi @ x + Gam @ (0.5 * (u[k] + u[min(k + 1, n - 1)])) + Lq @ rng.normal(size=2)
    xs = np.array(xs)
    y = np.column_stack([xs, xs @ A[0] + u @ B[0]])
    z = y + rng.normal(0, [0.002, 0.002, 0.02], y.shape)
    return fwid.Experiment(t, u, z, x0=np.zeros(2))


def test_riccati_solution_is_scipys_and_its_derivatives_equal_finite_differences():
    """Eq. (5.15) solved by Potter's method against scipy, for a stable and an unstable A,
    with and without process noise; the gain's derivatives (implicit function theorem, forward
    and reverse mode) against central finite differences."""
    C = np.array([[-1.2, 0.0], [1.0, 0.0], [0.0, 1.0]])
    R, dt = np.diag([0.1, 0.05, 0.001]), 0.05
    solve = jax.jit(care)
    for A in (np.array([[-1.2, 40.0], [0.25, -3.0]]), np.array([[-4.0, 1.0], [-0.5, -0.8]])):
        for FF in (np.diag([0.5, 0.01]), np.diag([100.0, 1.0])):
            P = scipy.linalg.solve_continuous_are(A.T, C.T, FF, R * dt)
            P2 = solve(jnp.asarray(A), jnp.asarray(C.T @ np.linalg.solve(R, C) / dt),
                       jnp.asarray(FF))
            assert np.max(np.abs(P2 - P)) <= 1e-12 * np.max(np.abs(P))

    @jax.jit
    def gain(th):
        A = jnp.array([[th[0], 40.0], [th[1], -3.0]])
        return steady_state_gain(A, jnp.asarray(C), jnp.diag(th[2:4] ** 2), jnp.diag(th[4:]),
                                 dt)[0]

    th = jnp.array([-1.2, 0.25, 0.7, 0.1, 0.1, 0.05, 0.001])
    h = 1e-7 * np.maximum(np.abs(np.asarray(th)), 1e-2)
    fd = np.stack([(gain(th.at[i].add(h[i])) - gain(th.at[i].add(-h[i]))) / (2 * h[i])
                   for i in range(th.shape[0])], -1)
    for J in (jax.jit(jax.jacfwd(gain))(th), jax.jit(jax.jacrev(gain))(th)):
        assert np.max(np.abs(J - fd)) <= 1e-6 * np.max(np.abs(fd))


def test_filter_error_gradients_equal_finite_differences():
    """The gradient of the filter-error likelihood (Eq. 5.36 at a fixed R) in the parameters
    and F, by autodiff through the filter, the matrix exponential and the Riccati solution,
    equals central finite differences to 1e-6 relative, forward and reverse mode."""
    e = _turbulent_flight()
    model = _model()
    batch = fwid.stack_experiments([e])
    R = jnp.diag(jnp.array([1e-3, 1e-3, 1e-1]))  # (the gain stays below 1: K C < I)
    p = len(model.free)

    @jax.jit
    def cost(theta):
        nu = _innovations(model, theta, R, batch, p)[0]
        return 0.5 * jnp.sum(nu @ jnp.linalg.inv(R) * nu)

    theta = jnp.array([*(0.9 * v for v in TRUE.values()), 0.1, 0.06])
    g_rev = jax.jit(jax.grad(cost))(theta)
    g_fwd = jax.jit(jax.jacfwd(cost))(theta)
    step = 1e-6 * np.maximum(np.abs(np.asarray(theta)), 1e-3)
    fd = np.array([(cost(theta.at[i].add(step[i])) - cost(theta.at[i].add(-step[i])))
                   / (2 * step[i]) for i in range(theta.shape[0])])
    for g in (g_rev, g_fwd):
        rel = np.abs(np.asarray(g) - fd) / np.maximum(np.abs(fd), 1e-12)
        assert np.all(rel <= 1e-6), rel


def test_filter_error_recovers_a_model_flown_in_turbulence():
    e = _turbulent_flight()
    start = _model(Lp=-3.0, Lr=0.5, Lda=-7.0, Np=-0.3, Nr=-1.2, Ndr=-2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fem = fwid.fit(start, e, start="model", method="filter-error")
    assert bool(fem.converged) and fem.white, fem.whiteness
    for k, v in TRUE.items():  # each within 3 standard deviations, the best within 5 %
        i = fem.names.index(k)
        assert abs(float(fem.theta[i]) - v) < 3 * float(fem.std[i]), k
    for k in ("Lp", "Lda"):
        assert abs(float(fem.theta[fem.names.index(k)]) / TRUE[k] - 1) < 0.05, k
    # (output error on this flight: Lda -8.89, Ndr -3.56, Nr -0.52; benchmarks/
    # textbook_cases.py, row gust_fem_vs_oem, compares the two on many flights)
    assert np.all(np.asarray(fem.F) > 0) and fem.innovations.shape == (1, e.n, 3)


@pytest.mark.skipif(not tc04.CASE.available(), reason="textbook data not found (../shared)")
def test_tc04_filter_error_within_five_percent_of_the_book():
    r = tc04.records()[0]
    e = fwid.Experiment(r["t"], r["u"], r["z"], x0=r["x0"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fwid.fit(fwid_model(tc04.CASE), e, start="model", method="filter-error",
                       process_noise=tc04.F0)
    assert bool(res.converged)
    for k, v in BOOK_FEM.items():
        assert abs(float(res.theta[res.names.index(k)]) / v - 1) < 0.05, k


@pytest.mark.skipif(not tc02.CASE.available(), reason="textbook data not found (../shared)")
def test_tc02_filter_error_converges_stable_with_white_innovations():
    r = tc02.records()[0]
    e = fwid.Experiment(r["t"], r["u"], r["z"], x0=r["x0"])
    model = fwid_model(tc02.CASE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fwid.fit(model, e, start="model", method="filter-error",
                       process_noise=tc02.F0)
    assert bool(res.converged) and res.white, res.whiteness
    A, _ = res.model.state_matrices(res.model.params, {})
    assert np.all(np.linalg.eigvals(np.asarray(A)).real < 0)


def test_fit_each_by_filter_error_is_fit_on_each_flight():
    """`fit_each(method="filter-error")` (a loop over the flights) gives each flight's
    `fit(method="filter-error")`; an unknown method is a ValueError naming the choices."""
    flights = [_turbulent_flight(seed=s) for s in (0, 1)]
    start = _model(Lp=-3.0, Lr=0.5, Lda=-7.0, Np=-0.3, Nr=-1.2, Ndr=-2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        each = fwid.fit_each(start, flights, start="model", method="filter-error")
        alone = [fwid.fit(start, e, start="model", method="filter-error") for e in flights]
    assert len(each) == 2
    for a, b in zip(each, alone):
        assert isinstance(a, fwid.FilterErrorResult) and a.names == b.names
        np.testing.assert_allclose(np.asarray(a.theta), np.asarray(b.theta), rtol=1e-8)
    # the two flights differ: each got its own fit
    assert not np.allclose(np.asarray(each[0].theta), np.asarray(each[1].theta))
    with pytest.raises(ValueError, match="'filter-error'"):
        fwid.fit_each(start, flights, method="kalman")


def test_filter_error_with_bias_terms_per_flight():
    """`local_per_flight=True`: a local parameter (here a bias of the measured roll
    acceleration, different on each flight) is estimated per flight (`bz@0`, `bz@1`, as in
    output error's joint fits); by default it is shared (`bz`)."""
    def h(x, u, p, c):
        return _h(x, u, p, c) + jnp.stack([0.0, 0.0, p["bz"]])

    model = fwid.GreyBoxModel(_f, h=h, states=("p", "r"), inputs=("da", "dr"),
                              outputs=("p", "r", "pdot"), params={**TRUE, "bz": 0.0},
                              local=("bz",), name="rollyaw-bias")
    flights = []
    for seed, b in ((0, 0.05), (1, -0.03)):
        e = _turbulent_flight(seed=seed)
        flights.append(fwid.Experiment(e.t, e.u, e.z.at[:, 2].add(b), x0=e.x0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        per = fwid.fit_filter_error(model, flights, names=["a", "b"], start="model",
                                    local_per_flight=True)
        shared = fwid.fit_filter_error(model, flights, names=["a", "b"], start="model")
        via_fit = fwid.fit(model, flights, start="model", method="filter-error",
                           local_per_flight=True)
    assert via_fit.names == per.names
    np.testing.assert_allclose(np.asarray(via_fit.theta), np.asarray(per.theta), rtol=1e-8)
    assert per.names[:len(TRUE)] == tuple(TRUE) and "bz" not in per.names
    for name, b in (("bz@0", 0.05), ("bz@1", -0.03)):
        assert abs(float(per.theta[per.names.index(name)]) - b) < 0.01, name
    assert float(per.flight_model(1).params["bz"]) == float(per.theta[per.names.index("bz@1")])
    assert "bz" in shared.names and "bz@0" not in shared.names
    assert per.cost < shared.cost


def test_a_fit_that_never_moves_is_not_converged(monkeypatch):
    """Gauss-Newton passes whose every step fails leave the estimates at the start: that is a
    stall, however settled R looks, and the result says so (the same flight converges when
    the steps go through)."""
    from fwid.estimate import _filter_error

    e = _turbulent_flight()
    start = _model(Lp=-3.0, Lr=0.5, Lda=-7.0, Np=-0.3, Nr=-1.2, Ndr=-2.0)
    real = _filter_error._inner

    def stalled(model, theta0, batch, Rk, **kw):
        out = dict(real(model, theta0, batch, Rk, **kw))
        out.update(theta=theta0, accepted=0, converged=False)
        return out

    monkeypatch.setattr(_filter_error, "_inner", stalled)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fem = fwid.fit(start, e, start="model", method="filter-error")
    assert not bool(fem.converged)


def test_unstable_closed_loop_flight_converges_from_equation_error():
    """A Flapper-like vehicle whose short oscillation is unstable, flown 20 s in closed loop
    through turbulence (the flights of benchmarks/filter_error_start.py): from the
    equation-error start filter error converges (from the book's start, R from the open-loop
    simulation, it did not: the benchmark's "before") and finds the unstable mode."""
    import filter_error_start as bench

    f = bench.flight("flapper-unstable", 3)
    model = fwid.longitudinal(bench.FLAPPER)
    exp = fwid.Experiment(f["t"], f["u"], f["z"], x0=f["z"][0], consts=f["consts"],
                          forces=f["forces"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fwid.fit(model.with_params({k: 0.0 for k in model.local}), exp,
                       method="filter-error")
    assert bool(res.converged) and res.gain in ("book", "bounded")
    eig = np.asarray(fwid.eigenvalues(res.model, f["consts"]))
    osc = eig[np.abs(eig.imag) > 1e-9][0]
    true = complex(*next(e for e in f["eig"] if abs(e[1]) > 1e-9))
    assert osc.real > 0 and abs(abs(osc) / abs(true) - 1) < 0.05
