"""Sensitivities by autodiff (fwid.sensitivity) against finite differences.

One simulated DelFly flight and one tight fit are shared by the whole module (compiled once).
Finite differences are central, with a relative step of 1e-5 (float64, smooth functions: the
truncation error is ~1e-10 relative, rounding dominates); they are compared on the entries
that are not tiny (above 1e-2 of the largest of their kind).

Measured on the embedded flight (lon_0, seed 0), max relative error against FD: outputs
w.r.t. parameters 6e-7, constants 1e-8, initial state 2e-9; eigenvalues 3e-9, wn 1e-8, zeta
5e-10; cost (R fixed 4e-7, R from Eq. 11 3e-6) and rms/rms_pct/r2/corr 2e-6 or less;
d theta_hat / d cutoff (R relaxed) against refits with fwid.fit, Richardson-extrapolated
central differences with steps 0.01 and 0.02 Hz: 5e-5, and 6e-7 once each refit is polished
by a few Newton steps on the same cost (fwid.fit stops at ~1e-7 relative in the parameters;
a plain 0.01 Hz central difference is off by 6e-4 because the estimates curve with the
cut-off); with R fixed, against the roots of the fixed-R gradient: 1e-7.
"""

from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.simulation import averaged
from fwid.synth import write_flights
from fwid.sensitivity import (
    cutoff_cost,
    eigenvalue_sensitivity,
    estimate_sensitivity_to_cutoff,
    metric_sensitivity,
    output_sensitivity,
    rank_sensitivities,
)

TIGHT = dict(rtol=1e-12, cost_rtol=1e-15, max_passes=30)
REL = 1e-5  # relative finite-difference step
CUTOFF = 5.0


def _step(value, name=""):
    """Relative step; the bias terms (which the outputs are affine in, so any step is exact
    but for rounding) are stepped on their natural scale, 1e-2."""
    value = abs(float(value))
    return REL * (max(value, 1e-2) if name.startswith("b") else value)


def _rel_err(ad, fd, frac=1e-2):
    """Max relative error over the entries of `ad` above `frac` of its largest entry."""
    ad, fd = np.asarray(ad), np.asarray(fd)
    big = np.abs(ad) > frac * np.abs(ad).max()
    assert big.any()
    return float(np.max(np.abs(fd[big] - ad[big]) / np.abs(ad[big])))


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    path = write_flights(tmp_path_factory.mktemp("sens"), 1, "lon", seed=0)[0]
    flight = fwid.load_flight(path)
    model = fwid.longitudinal()
    exp = averaged(flight, model, CUTOFF)
    fit = fwid.fit(model, exp, **TIGHT)
    assert bool(fit.converged)
    sim = jax.jit(lambda p, e: fwid.simulate(model, e, p)[1])
    return SimpleNamespace(flight=flight, model=model, exp=exp, fit=fit, sim=sim)


# -- 1. outputs ------------------------------------------------------------------------
def test_output_sensitivity_params(case):
    m, e = case.fit.model, case.exp
    S = output_sensitivity(m, e)
    assert tuple(S) == m.free
    worst = 0.0
    for k, ad in S.items():
        assert ad.shape == e.z.shape
        h = _step(m.params[k], k)
        yp = case.sim({**m.params, k: m.params[k] + h}, e)
        ym = case.sim({**m.params, k: m.params[k] - h}, e)
        worst = max(worst, _rel_err(ad, (yp - ym) / (2 * h)))
    print(f"outputs vs params: max rel err {worst:.1e}")
    assert worst < 1e-5


def test_output_sensitivity_consts_and_x0(case):
    m, e = case.fit.model, case.exp
    S = output_sensitivity(m, e, wrt="consts", names=["u0", "w0", "theta0", "mass", "Iy"])
    worst = 0.0
    for k, ad in S.items():
        h = _step(e.consts[k])
        ep = fwid.Experiment(e.t, e.u, e.z, e.x0, {**e.consts, k: e.consts[k] + h})
        em = fwid.Experiment(e.t, e.u, e.z, e.x0, {**e.consts, k: e.consts[k] - h})
        worst = max(worst, _rel_err(ad, (case.sim(m.params, ep) - case.sim(m.params, em))
                                    / (2 * h)))
    print(f"outputs vs consts: max rel err {worst:.1e}")
    assert worst < 1e-5
    S0 = output_sensitivity(m, e, wrt="x0")
    assert tuple(S0) == m.states
    worst0 = 0.0
    for i, k in enumerate(m.states):
        h = 1e-5
        ep = fwid.Experiment(e.t, e.u, e.z, e.x0.at[i].add(h), e.consts)
        em = fwid.Experiment(e.t, e.u, e.z, e.x0.at[i].add(-h), e.consts)
        worst0 = max(worst0, _rel_err(S0[k], (case.sim(m.params, ep) - case.sim(m.params, em))
                                      / (2 * h)))
    print(f"outputs vs x0: max rel err {worst0:.1e}")
    assert worst0 < 1e-5
    # at t0 the output is the initial state: dy(0)/dx0 = I
    np.testing.assert_allclose(np.stack([S0[k][0] for k in m.states]), np.eye(4), atol=1e-12)


# -- 2. eigenvalues --------------------------------------------------------------------
def _eigs(model, params, consts):
    return fwid.eigenvalues(model, consts, params)


def _matched(ev, ref):
    return np.array([ev[np.argmin(np.abs(ev - r))] for r in ref])


def test_eigenvalue_sensitivity(case):
    m, consts = case.fit.model, case.exp.consts
    sens = eigenvalue_sensitivity(m, consts)
    ev = sens["eigenvalues"]
    np.testing.assert_allclose(ev, fwid.eigenvalues(m, consts), rtol=1e-12)
    assert set(sens["names"]) == set(m.free) | set(consts)
    sp = sens["modes"][sens["short_period"]]
    assert sp["kind"] == "oscillatory" and sens["eigenvalues"][sp["index"]].imag > 0
    # normalised (p d/dp) sensitivities over all names, autodiff and finite differences
    ad = {"eig": [], "wn": [], "zeta": []}
    fd = {"eig": [], "wn": [], "zeta": []}
    for k in sens["names"]:
        p = sens["values"][k]
        h = _step(p, k)
        if k in m.params:
            ep = _eigs(m, {**m.params, k: m.params[k] + h}, consts)
            em = _eigs(m, {**m.params, k: m.params[k] - h}, consts)
        else:
            ep = _eigs(m, None, {**consts, k: consts[k] + h})
            em = _eigs(m, None, {**consts, k: consts[k] - h})
        d = sens["d_eigenvalues"][k]
        np.testing.assert_array_equal(sens["d_real"][k], d.real)
        np.testing.assert_array_equal(sens["d_imag"][k], d.imag)
        if k in m.local:  # the biases do not enter A
            assert np.all(d == 0)
            np.testing.assert_allclose(_matched(ep, ev), ev, rtol=1e-13)
            continue
        ad["eig"].append(p * d)
        fd["eig"].append(p * (_matched(ep, ev) - _matched(em, ev)) / (2 * h))
        osc = [max((x for x in fwid.modes(e) if x["kind"] == "oscillatory"),
                   key=lambda x: x["wn"]) for e in (ep, em)]
        for q in ("wn", "zeta"):
            ad[q].append(p * sp["d_" + q][k])
            fd[q].append(p * (osc[0][q] - osc[1][q]) / (2 * h))
    worst = {q: _rel_err(np.array(ad[q]), np.array(fd[q])) for q in ad}
    print("eigenvalues: max rel err " + ", ".join(f"{q} {v:.1e}" for q, v in worst.items()))
    assert max(worst.values()) < 1e-5


def test_eigenvalue_sensitivity_known_modes():
    """x' = A x with a (wn, zeta) block and a real pole: the derivatives are known exactly."""

    def f(x, u, p, c):
        a, b, r = x
        return jnp.stack([b, -p["wn"] ** 2 * a - 2 * p["zeta"] * p["wn"] * b + u[0],
                          p["pole"] * r + c["k"] * u[0]])

    model = fwid.GreyBoxModel(f, states=("a", "b", "r"), inputs=("u",),
                              params=dict(wn=5.0, zeta=0.3, pole=-2.0), constants=("k",))
    sens = eigenvalue_sensitivity(model, {"k": 1.0})
    osc = sens["modes"][sens["short_period"]]
    (aper,) = [m for m in sens["modes"] if m["kind"] == "aperiodic"]
    assert osc["d_wn"] == pytest.approx({"wn": 1.0, "zeta": 0.0, "pole": 0.0, "k": 0.0}, abs=1e-12)
    assert osc["d_zeta"] == pytest.approx({"wn": 0.0, "zeta": 1.0, "pole": 0.0, "k": 0.0},
                                          abs=1e-12)
    assert aper["d_eigenvalue"]["pole"] == pytest.approx(1.0, abs=1e-12)
    assert aper["d_tau"]["pole"] == pytest.approx(1 / 2.0**2, rel=1e-12)  # tau = -1/pole
    # d lambda / d zeta for lambda = -zeta wn + i wn sqrt(1 - zeta^2)
    wn, z = 5.0, 0.3
    expected = -wn - 1j * wn * z / np.sqrt(1 - z**2)
    assert osc["d_eigenvalue"]["zeta"] == pytest.approx(expected, rel=1e-12)
    assert dict(rank_sensitivities(sens, quantity="zeta"))["zeta"] == pytest.approx(1.0)
    assert dict(rank_sensitivities(sens, mode=1, quantity="tau"))["pole"] == pytest.approx(-1.0)


def test_rank_sensitivities(case):
    m, consts = case.fit.model, case.exp.consts
    sens = eigenvalue_sensitivity(m, consts)
    ranked = rank_sensitivities(sens)
    assert len(ranked) == len(sens["names"])
    mags = [abs(v) for _, v in ranked]
    assert mags == sorted(mags, reverse=True)
    sp = sens["modes"][sens["short_period"]]
    lam = sens["eigenvalues"][sp["index"]]
    # definition: |p dlambda/dp| / |lambda|
    k, v = ranked[0]
    assert v == pytest.approx(abs(sens["values"][k] * sp["d_eigenvalue"][k]) / abs(lam), rel=1e-12)
    # the biases do not move the modes; the pitch damping Mq does
    top = [name for name, _ in ranked[:6]]
    assert "Mq" in top
    assert all(v == 0 for name, v in ranked if name.startswith("b"))
    # Euler's theorem for A's homogeneity: scaling (Mq, Mu, Mw, Mde) and Iy together leaves A
    # unchanged, so the normalised sensitivities of the M-derivatives sum to minus Iy's.
    wn = dict(rank_sensitivities(sens, quantity="wn"))
    assert sum(wn[k] for k in ("Mq", "Mu", "Mw", "Mde")) == pytest.approx(-wn["Iy"], rel=1e-9)
    params_only = rank_sensitivities(sens, quantity="zeta", names=m.free)
    assert {n for n, _ in params_only} == set(m.free)
    with pytest.raises(ValueError):
        rank_sensitivities(sens, quantity="tau")
    with pytest.raises(ValueError):
        rank_sensitivities(sens, quantity="speed")


# -- 3. fit metrics --------------------------------------------------------------------
def _np_cost(z, y, R):
    v = np.asarray(z) - np.asarray(y)
    R = np.asarray(R)
    N, ny = v.shape
    return (0.5 * np.einsum("ki,ij,kj->", v, np.linalg.inv(R), v)
            + 0.5 * N * np.linalg.slogdet(R)[1] + 0.5 * N * ny * np.log(2 * np.pi))


def _np_metrics(z, y, names, R):
    fm = fwid.fit_metrics(np.asarray(z), np.asarray(y), names)
    out = {q: np.array([fm[n][q] for n in names]) for q in ("rms", "rms_pct", "r2", "corr")}
    out["cost"] = _np_cost(z, y, R)
    v = np.asarray(z) - np.asarray(y)
    out["cost_relaxed"] = _np_cost(z, y, v.T @ v / v.shape[0])
    return out


def test_metric_sensitivity(case):
    e, fit = case.exp, case.fit
    # away from the optimum (Table 1 aerodynamics, fitted biases), so the gradient is not ~0
    m = fwid.longitudinal().with_params({k: fit.model.params[k] for k in case.model.local})
    ms = metric_sensitivity(m, e, R=fit.R)
    relaxed = metric_sensitivity(m, e)
    names = m.outputs
    base = _np_metrics(e.z, case.sim(m.params, e), names, fit.R)
    for q in ("rms", "rms_pct", "r2", "corr", "cost"):
        np.testing.assert_allclose(ms[q]["value"], base[q], rtol=1e-10)
    np.testing.assert_allclose(relaxed["cost"]["value"], base["cost_relaxed"], rtol=1e-12)
    quantities = ("rms", "rms_pct", "r2", "corr", "cost", "cost_relaxed")
    ad = {q: [] for q in quantities}
    fd = {q: [] for q in quantities}
    for k in m.free:  # normalised (p d/dp), over parameters and outputs
        p = float(m.params[k])
        h = _step(p, k)
        yp = case.sim({**m.params, k: m.params[k] + h}, e)
        ym = case.sim({**m.params, k: m.params[k] - h}, e)
        mp, mm = _np_metrics(e.z, yp, names, fit.R), _np_metrics(e.z, ym, names, fit.R)
        for q in quantities:
            ad[q].append(p * np.asarray((relaxed["cost"] if q == "cost_relaxed" else ms[q])
                                        ["grad"][k]))
            fd[q].append(p * (mp[q] - mm[q]) / (2 * h))
    worst = {q: _rel_err(np.array(ad[q]), np.array(fd[q])) for q in quantities}
    print("metrics: max rel err " + ", ".join(f"{q} {v:.1e}" for q, v in worst.items()))
    assert max(worst.values()) < 1e-5


def test_metric_cost_at_the_estimate(case):
    """At the fit, Eq. 10 with R from Eq. 11 is fwid.fit's cost, and it is stationary."""
    ms = metric_sensitivity(case.fit.model, case.exp)
    assert float(ms["cost"]["value"]) == pytest.approx(float(case.fit.cost), rel=1e-12)
    grad = np.array([ms["cost"]["grad"][k] for k in case.fit.names])
    # compare with the gradient one standard deviation away from the estimate, per parameter
    assert np.all(np.abs(grad * np.asarray(case.fit.std_cr)) < 1e-5)


# -- 4. estimates vs the split cut-off -------------------------------------------------
@pytest.fixture(scope="module")
def refits(case):
    """Refits with fwid.fit at 5 +- 0.01 and 5 +- 0.02 Hz, warm-started at the estimate."""
    out = {}
    for c in (CUTOFF - 0.02, CUTOFF - 0.01, CUTOFF + 0.01, CUTOFF + 0.02):
        r = fwid.fit(case.model, averaged(case.flight, case.model, c), start=case.fit.model,
                     **TIGHT)
        out[c] = np.asarray(r.theta)
    return out


def _richardson(theta_of, h):
    def D(s):
        return (theta_of(CUTOFF + s) - theta_of(CUTOFF - s)) / (2 * s)

    return (4 * D(h) - D(2 * h)) / 3, D(h)


def _chord_newton(grad, H, theta, c, iters=4):
    for _ in range(iters):
        theta = theta - np.linalg.solve(H, np.asarray(grad(theta, c)))
    return theta


@pytest.fixture(scope="module")
def relaxed(case):
    return estimate_sensitivity_to_cutoff(case.model, case.flight, case.fit, CUTOFF)


def test_cutoff_derivative_matches_refits(case, refits, relaxed):
    cs = relaxed
    assert cs["names"] == case.fit.names
    d = cs["d_theta"]
    assert np.all(np.isfinite(d)) and np.all(d != 0)
    assert np.max(np.abs(cs["newton_step"] / cs["theta"])) < 1e-6  # the fit is converged
    rich, plain = _richardson(lambda c: refits[c], 0.01)
    err_raw = float(np.max(np.abs(rich - d) / np.abs(d)))
    err_plain = float(np.max(np.abs(plain - d) / np.abs(d)))
    # polish each refit to the exact stationary point of the same cost (chord Newton with the
    # Hessian at 5 Hz: the root is set by the gradient alone)
    grad = jax.jit(jax.jacfwd(cutoff_cost(case.model, case.flight, case.fit)))
    polished = {c: _chord_newton(grad, cs["hessian"], th, c) for c, th in refits.items()}
    for c, th in polished.items():
        assert np.max(np.abs(np.asarray(grad(th, c)) * case.fit.std_cr)) < 1e-9
    rich_pol, _ = _richardson(lambda c: polished[c], 0.01)
    err_pol = float(np.max(np.abs(rich_pol - d) / np.abs(d)))
    print(f"cutoff: fwid.fit refits, Richardson {err_raw:.1e} (plain 0.01 Hz {err_plain:.1e});"
          f" polished refits, Richardson {err_pol:.1e}")
    assert err_pol < 1e-5
    assert err_raw < 5e-4


def test_cutoff_derivative_fixed_R(case, relaxed):
    """With R held at the fit's R: against the roots of the fixed-R gradient at c +- h."""
    cs = estimate_sensitivity_to_cutoff(case.model, case.flight, case.fit, CUTOFF, noise="fixed")
    d = cs["d_theta"]
    L = cutoff_cost(case.model, case.flight, case.fit, noise="fixed")
    grad = jax.jit(jax.jacfwd(L))
    # the fit's R is Eq. 11 at the estimate: the estimate is also the fixed-R stationary point
    assert np.max(np.abs(cs["newton_step"] / cs["theta"])) < 1e-6
    th = {c: _chord_newton(grad, cs["hessian"], np.asarray(case.fit.theta), c, iters=6)
          for c in (CUTOFF - 0.02, CUTOFF - 0.01, CUTOFF + 0.01, CUTOFF + 0.02)}
    rich, _ = _richardson(lambda c: th[c], 0.01)
    err = float(np.max(np.abs(rich - d) / np.abs(d)))
    print(f"cutoff, R fixed: max rel err {err:.1e}")
    assert err < 1e-5
    # R's own movement with the cut-off is not negligible: the two derivatives differ
    assert np.max(np.abs(d - relaxed["d_theta"]) / np.abs(relaxed["d_theta"])) > 0.1
    # value of L at the estimate is the data term with the fit's R: N ny / 2
    N, ny = case.exp.z.shape
    assert float(L(case.fit.theta, CUTOFF)) == pytest.approx(0.5 * N * ny, rel=1e-6)


def test_cutoff_cost_several_flights(case):
    """Joint-fit layout (biases per flight, `bq@0`, `bq@1`, ...) and padding of flights of
    different lengths: with R fixed the cost of two flights is the sum of their costs."""
    m, fit, fl = case.model, case.fit, case.flight
    short = fl.slice(0, fl.n - 150)
    glob = [k for k in m.free if k not in m.local]
    names = tuple(glob) + tuple(f"{k}@{i}" for k in m.local for i in range(2))
    theta = np.concatenate([np.asarray(fit.theta)[:len(glob)],
                            np.repeat([float(fit.model.params[k]) for k in m.local], 2)])
    joint = SimpleNamespace(names=names, model=fit.model, R=fit.R)
    L2 = cutoff_cost(m, [fl, short], joint, noise="fixed")
    L1 = cutoff_cost(m, fl, fit, noise="fixed")
    L1s = cutoff_cost(m, short, fit, noise="fixed")
    total = float(L1(fit.theta, CUTOFF)) + float(L1s(fit.theta, CUTOFF))
    assert float(L2(theta, CUTOFF)) == pytest.approx(total, rel=1e-12)
    with pytest.raises(ValueError):  # per-flight biases of two flights, one flight given
        cutoff_cost(m, fl, joint)


# -- errors ----------------------------------------------------------------------------
def test_errors(case):
    m, e = case.model, case.exp
    with pytest.raises(ValueError):
        output_sensitivity(m, e, wrt="trim")
    with pytest.raises(KeyError):
        output_sensitivity(m, e, names=["nope"])
    with pytest.raises(ValueError):
        output_sensitivity(m, fwid.stack_experiments([e, e]))
    with pytest.raises(KeyError):
        eigenvalue_sensitivity(m, {"mass": 1.0})
    with pytest.raises(ValueError):
        cutoff_cost(m.with_free(("Mq", "Mde")), case.flight, case.fit)
    with pytest.raises(ValueError):
        cutoff_cost(m, case.flight, case.fit, noise="white")
