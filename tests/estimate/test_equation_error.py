"""Equation error (`fwid.fit(method="equation-error")`): least squares of the reconstructed
loads on the measured states (the paper's Eqs. 1-6), the state equations for the biases."""

import sys
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.simulation import Experiment

from .conftest import LON_CONSTS, LON_TRUE, make_flight

AERO = ("Xq", "Xu", "Xw", "Xde", "Zq", "Zu", "Zw", "Zde", "Mq", "Mu", "Mw", "Mde")


def _fit(exps, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fwid.fit(fwid.longitudinal(), exps, method="equation-error",
                        names=[f"f{i}" for i in range(len(exps))], **kw)


def test_recovers_the_true_parameters_of_a_noise_free_flight():
    fl = make_flight("lon")
    res = _fit([fl.experiment(forces=True)])
    assert bool(res.converged) and int(res.steps) == 1
    got = dict(zip(res.names, np.asarray(res.theta)))
    for k in AERO:  # the loads are exactly linear in the states: exact to rounding
        assert got[k] == pytest.approx(LON_TRUE[k], rel=1e-8, abs=1e-12), k
    for k in ("bq", "bu", "bw", "btheta"):  # through differentiated states: close
        assert got[k] == pytest.approx(LON_TRUE[k], rel=0.03, abs=2e-4), k


def _noisy_flights(seed=0, colour=1):
    rng = np.random.default_rng(seed)
    exps = []
    for shift, scale in ((0.0, 1.0), (0.7, -1.3)):
        fl = make_flight("lon")
        u = np.roll(fl.u, int(shift / 0.005)) * scale
        fl = type(fl)(fl.model, u, LON_CONSTS)
        noise = rng.normal(size=fl.forces.shape) * fl.forces.std(axis=0) * 0.2
        if colour > 1:  # a moving average: residuals correlated over `colour` samples
            kernel = np.ones(colour) / np.sqrt(colour)
            noise = np.stack([np.convolve(c, kernel, "same") for c in noise.T], axis=1)
        offset = np.array([0.01, -0.02, 3e-4]) * (1 + len(exps))  # each flight's trim error
        exps.append(Experiment(fl.t, fl.u, fl.ys, fl.x0, fl.consts,
                               forces=fl.forces + noise + offset))
    return exps


def test_agrees_with_an_independent_numpy_least_squares_to_1e_8():
    exps = _noisy_flights()
    res = _fit(exps)
    got = dict(zip(res.names, np.asarray(res.theta)))
    # numpy: each load on q, u, w, de and one intercept per flight, stacked over the flights
    for j, load in enumerate("XZM"):
        rows, y = [], []
        for i, e in enumerate(exps):
            z, u = np.asarray(e.z), np.asarray(e.u)
            icpt = np.zeros((len(z), len(exps)))
            icpt[:, i] = 1.0
            rows.append(np.column_stack([z[:, 0], z[:, 1], z[:, 2], u[:, 0], icpt]))
            y.append(np.asarray(e.forces)[:, j])
        beta = np.linalg.lstsq(np.vstack(rows), np.concatenate(y), rcond=None)[0]
        for k, b in zip(("q", "u", "w", "de"), beta[:4]):
            assert got[f"{load}{k}"] == pytest.approx(b, rel=1e-8, abs=1e-14), f"{load}{k}"


def test_each_flight_has_its_own_biases_and_a_joint_model_per_flight():
    exps = _noisy_flights()
    res = _fit(exps)
    assert [n for n in res.names if "@" in n] == [
        f"{b}@{i}" for b in ("bq", "bu", "bw", "btheta") for i in (0, 1)]
    assert float(res.flight_model(1).params["bq"]) == float(res.theta[res.names.index("bq@1")])
    shared = _fit(exps, local_per_flight=False)
    assert "bq" in shared.names and "bq@0" not in shared.names


def test_standard_deviations_allow_for_coloured_residuals():
    white = _fit(_noisy_flights(colour=1))
    coloured = _fit(_noisy_flights(colour=15))
    i = [white.names.index(k) for k in AERO]
    ratio_white = np.asarray(white.std)[i] / np.asarray(white.std_cr)[i]
    ratio_coloured = np.asarray(coloured.std)[i] / np.asarray(coloured.std_cr)[i]
    assert np.all((ratio_white > 0.7) & (ratio_white < 1.4)), ratio_white
    assert np.median(ratio_coloured) > 2.0, ratio_coloured


def test_a_model_whose_states_are_not_measured_is_refused_in_one_line():
    model = fwid.GreyBoxModel(lambda x, u, p, c: jnp.stack([p["a"] * x[0] + u[0]]),
                              states=("x",), inputs=("u",), params={"a": -1.0},
                              h=lambda x, u, p, c: jnp.stack([2.0 * x[0]]), outputs=("y",))
    t = np.arange(100) * 0.01
    exp = Experiment(t, np.sin(t), np.cos(t), x0=np.zeros(1))
    with pytest.raises(fwid.InputError, match="equation error regresses the measured state"):
        fwid.fit(model, exp, method="equation-error")


sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from cases import tc04  # noqa: E402
from cases.textbook import fwid_model  # noqa: E402


def test_textbook_hfb320_agrees_with_an_independent_regression():
    """FVSysID TC04 (HFB-320): the state equations regressed on the measured states, against
    numpy's least squares of the same regression (finite-difference regressors of the
    case's own numpy equations, the same per-equation weights)."""
    if not tc04.CASE.available():
        pytest.skip("textbook flight data not found beside the repository (../shared)")
    case = tc04.CASE
    rec = case.records()[0]
    model = fwid_model(case)
    exp = Experiment(rec["t"], rec["u"], rec["z"], x0=rec["x0"], consts=rec["consts"])
    res = fwid.fit(model, exp, method="equation-error")
    # numpy: the measured states (V, alpha, theta, q are outputs 0-3), their central
    # differences, and f's regressors by finite differences of the case's numpy xdot
    x, u, t = rec["z"][:, :4], rec["u"], rec["t"]
    xdot = np.gradient(x, t, axis=0)
    th0 = np.asarray(case.theta0, float)
    free = list(model.free)

    def f(th):
        p = dict(zip(case.names, th))
        return case.xdot(x, u, p, {}, np)

    f0 = f(th0)
    cols = []
    for k in free:
        th = th0.copy()
        i = list(case.names).index(k)
        th[i] += 1e-3 * max(1.0, abs(th0[i]))
        cols.append((f(th) - f0) / (th[i] - th0[i]))
    S = np.stack(cols, axis=-1)  # (n, 4, p)
    r = xdot - f0
    w = np.ones(4)
    for _ in range(3):  # the weights relaxed to each equation's residual rms
        A = (S * w[None, :, None]).reshape(-1, len(free))
        step = np.linalg.lstsq(A, (r * w).ravel(), rcond=None)[0]
        v = r - S @ step
        w = 1.0 / np.sqrt(np.mean(v**2, axis=0))
    want = th0[[list(case.names).index(k) for k in free]] + step
    np.testing.assert_allclose(np.asarray(res.theta), want, rtol=1e-8, atol=1e-12)


def test_twin_otter_regression_is_sidpacs():
    """SIDPAC's `totter_demo.m` (Twin Otter manoeuvre 020213f1_018): its equation-error
    estimates of the pitching-moment and Z-force coefficients on alpha, qhat and the
    elevator with a bias (`totter_results.mat`: `pm`, `pZ`, standard errors `serrm`,
    `serrZ`), from fwid's equation error on a model whose loads are those coefficients."""
    import scipy.io

    from cases.textbook import data_root

    root = data_root() / "sidpac_v1_twin_otter"
    if not (root / "totter_results.mat").exists():
        pytest.skip("textbook flight data not found beside the repository (../shared)")
    fd = scipy.io.loadmat(root / "totter_lon_020213f1_018.mat")["fdata"]
    book = scipy.io.loadmat(root / "totter_results.mat")
    dtr = np.pi / 180
    t, z = fd[:, 0] - fd[0, 0], np.stack([fd[:, 3] * dtr, fd[:, 71]], 1)  # alpha, qhat

    def loads(x, u, p, c):
        return jnp.stack([p["CZa"] * x[0] + p["CZq"] * x[1] + p["CZde"] * u[0],
                          p["Cma"] * x[0] + p["Cmq"] * x[1] + p["Cmde"] * u[0]])

    names = ("CZa", "CZq", "CZde", "Cma", "Cmq", "Cmde")
    model = fwid.GreyBoxModel(lambda x, u, p, c: jnp.zeros(2), states=("alpha", "qhat"),
                              inputs=("de",), params=dict.fromkeys(names, 0.0),
                              forces=loads, force_names=("CZ", "Cm"))
    exp = Experiment(t, fd[:, 13] * dtr, z, x0=z[0], forces=fd[:, [62, 64]])
    res = fwid.fit(model, exp, method="equation-error")
    got = dict(zip(res.names, np.asarray(res.theta)))
    std = dict(zip(res.names, np.asarray(res.std)))
    want = dict(zip(names, [*book["pZ"].ravel()[:3], *book["pm"].ravel()[:3]]))
    serr = dict(zip(names, [*book["serrZ"].ravel()[:3], *book["serrm"].ravel()[:3]]))
    for k in ("Cma", "Cmq", "Cmde"):  # the same regression: to rounding
        assert got[k] == pytest.approx(want[k], rel=1e-9), k
    for k in ("CZa", "CZq", "CZde"):  # SIDPAC's CZ differs from the file's by a little
        assert got[k] == pytest.approx(want[k], rel=5e-3), k
    for k in names:  # coloured-residual std: SIDPAC's r_colores, a different lag window
        assert 0.6 < std[k] / serr[k] < 1.4, (k, std[k], serr[k])
