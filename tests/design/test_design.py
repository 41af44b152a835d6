"""The D-optimal design: its gradient, its limits, a known analytic optimum."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.design._design import criterion
from fwid.design._information import Setting
from fwid.design._signals import Grid, input_3211, steps


@pytest.fixture(scope="module")
def design(report_path):
    return fwid.design_input(str(report_path), duration=3.0, amplitude=0.1, quiet=0.5,
                             rate=50.0, restarts=2, iterations=100, switch_rate=8.0)


@pytest.fixture(scope="module")
def lon_setting(report_path):
    from fwid.design._source import from_report

    model, consts, R, _ = from_report(str(report_path))
    return Setting(model.with_params(bq=0.0, bu=0.0, bw=0.0, btheta=0.0), consts, R, "de")


def _central_differences(f, x, idx, h=1e-5):
    out = []
    for i in idx:
        e = jnp.zeros_like(x).at[i].set(h)
        out.append((f(x + e) - f(x - e)) / (2 * h))
    return np.array([float(v) for v in out])


@pytest.mark.parametrize("kind", ["d-optimal", "variances"])
def test_gradient_of_the_criterion_equals_finite_differences(lon_setting, kind):
    """Through the precomputed responses of the longitudinal model (the default path)."""
    from fwid.design._affine import affine_responses
    from fwid.design._criterion import AffineLoss, parametrisation

    grid = Grid(3.0, 0.5, 50.0)  # the `design` fixture's: its compiled solves are reused
    basis, coef, _ = parametrisation("steps", grid, 0.1, 8.0, None)
    affine, _ = affine_responses(lon_setting, grid.t, basis, 0.1)
    loss = AffineLoss(affine, coef, jnp.zeros((12, 12)), jnp.asarray(0.02), 3,
                      lon_setting.glob, lon_setting.loc, kind)
    x = jnp.asarray(np.random.default_rng(1).normal(size=20))
    g = jax.grad(loss)(x)
    idx = (0, 4, 9, 19)
    np.testing.assert_allclose(np.asarray(g)[list(idx)],
                               _central_differences(eqx.filter_jit(loss), x, idx), rtol=1e-5,
                               atol=1e-8)
    assert float(jnp.max(jnp.abs(g))) > 1e-3  # not trivially zero


def test_gradient_through_the_simulation_equals_finite_differences():
    """Through the RK4 solve and its sensitivities (the path of a model not affine in the
    input): a first-order model with a quadratic term."""
    def f(x, u, p, c):
        return jnp.stack([p["a"] * x[0] + p["b"] * u[0] + p["c"] * x[0] ** 2])

    model = fwid.GreyBoxModel(f, states=("x",), inputs=("u",),
                              params={"a": -2.0, "b": 1.5, "c": 0.5})
    setting = Setting(model, {}, [[1e-4]], "u")
    grid = Grid(2.0, 0.5, 20.0)

    def crit(x):
        return criterion(setting, grid.t, steps(x, grid, 5.0, 0.3))[0]

    x = jnp.asarray(np.random.default_rng(2).normal(size=8))
    g = jax.grad(crit)(x)
    idx = (0, 3, 7)
    np.testing.assert_allclose(np.asarray(g)[list(idx)], _central_differences(crit, x, idx),
                               rtol=1e-5, atol=1e-8)
    assert float(jnp.max(jnp.abs(g))) > 1e-3


def test_the_affine_information_equals_the_simulation_to_round_off(lon_setting):
    """The longitudinal model is affine in the input: the precomputed quadratic form gives
    the information and outputs of a direct solve of the sensitivities."""
    from fwid.design._affine import affine_responses
    from fwid.design._criterion import parametrisation
    from fwid.design._information import information

    grid = Grid(3.0, 0.5, 50.0)
    for name in ("steps", "multisine"):
        basis, _, _ = parametrisation(name, grid, 0.1, 8.0, (0.0, 3.0))
        affine, worst = affine_responses(lon_setting, grid.t, basis, 0.1)
        assert affine is not None and worst < 1e-10
        v = 0.1 * np.random.default_rng(3).uniform(-1, 1, basis.shape[0])
        M, ys = information(lon_setting, lon_setting.experiment(grid.t, v @ basis))
        np.testing.assert_allclose(np.asarray(affine.information(jnp.asarray(v))),
                                   np.asarray(M), rtol=1e-9, atol=1e-9 * float(M.max()))
        np.testing.assert_allclose(np.asarray(affine.outputs(jnp.asarray(v))), np.asarray(ys),
                                   rtol=1e-9, atol=1e-12)


def test_a_model_not_affine_in_the_input_is_designed_through_the_simulation():
    def f(x, u, p, c):
        return jnp.stack([p["a"] * x[0] + p["b"] * u[0] + 0.3 * u[0] ** 3])

    model = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"a": -2.0, "b": 1.5})
    kw = dict(consts={}, R=[[1e-3]], duration=2.0, quiet=0.5, amplitude=0.5, rate=20.0,
              switch_rate=5.0, attitude_limit=None, restarts=1, iterations=50)
    d = fwid.design_input(model, **kw)
    assert d.settings["affine_in_input"] is False
    assert d.settings["affine_check_rel"] > 1e-4
    with pytest.raises(fwid.InputError, match="not affine in the input"):
        fwid.design_input(model, fast=True, **kw)


def test_the_limits_hold(design):
    t, u = design.t, design.u
    assert t[0] == 0.0 and t[-1] <= 3.0 + 1e-12
    assert np.max(np.abs(u)) <= 0.1 + 1e-12
    assert np.all(u[t <= 0.5] == 0.0)
    assert np.max(np.abs(u)) > 0.05  # it does excite
    lim = design.limits
    theta = design.response[:, design.outputs.index("theta")]
    assert np.max(np.abs(theta)) <= lim["attitude_bound_rad"] * (1 + 1e-6)
    # the default bound: the 3211's own excursion
    assert lim["attitude_bound_rad"] == pytest.approx(lim["attitude_peak_3211_rad"])


def test_an_explicit_attitude_bound_holds_with_its_margin(report_path):
    d = fwid.design_input(str(report_path), duration=3.0, amplitude=0.1, quiet=0.5,
                          rate=50.0, restarts=2, iterations=50, switch_rate=8.0,
                          attitude_limit=0.05)  # one compiled chunk of 50 steps
    theta = d.response[:, d.outputs.index("theta")]
    assert np.max(np.abs(theta)) <= 0.8 * 0.05 * (1 + 1e-6)
    assert np.max(np.abs(theta)) >= 0.8 * 0.05 * 0.99  # the bound is what limits it


def test_the_design_beats_the_3211_it_reports(design):
    assert design.criterion > design.criterion_3211
    # the reported stds are the inverse information's (recomputed independently here)
    idx = [design.names.index(k) for k in design.vehicle_names]
    std = np.sqrt(np.diag(np.linalg.inv(design.information)))
    np.testing.assert_allclose(std, design.std[idx], rtol=1e-6)
    np.testing.assert_allclose(design.ratio, design.std_3211 / design.std)
    np.testing.assert_allclose(design.u_3211, input_3211(Grid(3.0, 0.5, 50.0), 0.1))


def test_flights_already_flown_add_their_information(report_path, design):
    """Designing after a flight of the same input: the information is the sum of both."""
    d2 = fwid.design_input(str(report_path), duration=3.0, amplitude=0.1, quiet=0.5,
                           rate=50.0, restarts=1, iterations=1, switch_rate=8.0,
                           flown=[(design.t, design.u)])
    from fwid.design._source import from_report
    from fwid.design._information import information, vehicle_information, absolute

    model, consts, R, _ = from_report(str(report_path))
    s = Setting(model.with_params(bq=0.0, bu=0.0, bw=0.0, btheta=0.0), consts, R, "de")
    M1 = absolute(s, vehicle_information(s, information(s, s.experiment(design.t, design.u))[0]),
                  s.glob)
    M2 = absolute(s, vehicle_information(s, information(s, s.experiment(d2.t, d2.u))[0]), s.glob)
    np.testing.assert_allclose(d2.information, M1 + M2, rtol=1e-6)


def test_first_order_system_optimum_is_a_over_root_3():
    """x' = a x + b u, y = x, a and b free. A steady sine `u = A sin(w t)` gives
    `x = b A / (jw - a)`, `dx/db = A / (jw - a)`, `dx/da = b A / (jw - a)^2`, so that
    `det M` is proportional to `|g2|^4 Im(b / (jw - a))^2 = b^2 w^2 / (w^2 + a^2)^4`,
    largest at `w = |a| / sqrt(3)` (Mehra's classic result). The criterion of single sines
    peaks there; under a peak bound a square wave carries more power than a sine, and the
    designed steps do better than the best sine, switching about as often as that sine."""
    a, b = -3.0, 2.0

    def f(x, u, p, c):
        return jnp.stack([p["a"] * x[0] + p["b"] * u[0]])

    model = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"a": a, "b": b})
    setting = Setting(model, {}, [[1e-4]], "u")
    grid = Grid(61.0, 1.0, 10.0)
    freqs = np.arange(1, 40) / 60.0  # harmonics of the window, 1/60 Hz apart
    tau = grid.t - 1.0
    sines = np.sin(2 * np.pi * freqs[:, None] * tau[None]) * grid.active
    crit = jax.jit(jax.vmap(lambda u: criterion(setting, grid.t, u)[0]))(jnp.asarray(sines))
    w_best = 2 * np.pi * freqs[int(np.argmax(np.asarray(crit)))]
    w_opt = abs(a) / np.sqrt(3)  # 1.732 rad/s, 0.2757 Hz
    assert abs(w_best - w_opt) <= 2 * np.pi / 60.0  # within one harmonic
    # the analytic shape: criterion differences follow log(w^2 / (w^2 + a^2)^4)
    w = 2 * np.pi * freqs[[6, 16, 30]]
    analytic = np.log(w**2 / (w**2 + a**2) ** 4)
    got = np.asarray(crit)[[6, 16, 30]]
    np.testing.assert_allclose(got - got[0], analytic - analytic[0], atol=0.05)
    d = fwid.design_input(model, consts={}, R=[[1e-4]], duration=61.0, quiet=1.0,
                          amplitude=1.0, rate=10.0, parametrisation="steps", switch_rate=2.0,
                          attitude_limit=None, restarts=2, iterations=300,
                          criterion="d-optimal")
    assert d.criterion >= float(np.max(np.asarray(crit)))
    u = d.u[grid.active > 0]
    switches = np.sum(np.sign(u[1:]) != np.sign(u[:-1])) / 60.0  # per second
    assert switches == pytest.approx(2 * w_opt / (2 * np.pi), rel=0.5)


def test_bad_limits_are_one_line_errors(report_path):
    with pytest.raises(fwid.InputError, match="amplitude must be > 0"):
        fwid.design_input(str(report_path), amplitude=-0.1)
    with pytest.raises(fwid.InputError, match="quiet start"):
        fwid.design_input(str(report_path), amplitude=0.1, duration=2.0, quiet=2.0)
    with pytest.raises(fwid.InputError, match="not 'lat'"):
        fwid.design_input(str(report_path), amplitude=0.1, model="lat")


def test_a_prior_as_strong_as_the_data_halves_the_variance():
    """One free parameter: prior information equal to the flight's halves the variance."""
    def f(x, u, p, c):
        return jnp.stack([p["a"] * x[0] + p["b"] * u[0]])

    model = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"a": -2.0, "b": 1.5},
                              free=("b",))
    kw = dict(consts={}, R=[[1e-3]], duration=3.0, quiet=0.5, amplitude=0.2, rate=20.0,
              attitude_limit=None, restarts=1, iterations=50)
    d0 = fwid.design_input(model, **kw)
    d1 = fwid.design_input(model, prior_information={"b": float(d0.std_3211[0])}, **kw)
    assert d1.std_3211[0] ** 2 == pytest.approx(d0.std_3211[0] ** 2 / 2, rel=1e-9)


def test_the_prior_of_a_report_is_read_as_stds():
    from tests.design.conftest import lon_report
    from fwid.design._source import report_prior

    rep = lon_report()
    assert report_prior(rep) is None
    rep["prior"] = {"Mq": {"mean": -1e-3, "std": 2e-4}, "Zw": {"mean": -0.07, "std": None}}
    assert report_prior(rep) == {"Mq": 2e-4}
