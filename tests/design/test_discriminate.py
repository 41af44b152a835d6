"""The discriminating design: two models that differ, told apart."""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid


def _first_order(b):
    def f(x, u, p, c):
        return jnp.stack([p["a"] * x[0] + p["b"] * u[0]])
    return fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"a": -2.0, "b": b})


def test_the_distance_is_the_noise_normalised_difference_and_beats_a_3211():
    ma, mb = _first_order(1.0), _first_order(1.2)
    d = fwid.design_discriminating(ma, mb, consts={}, R=[[1e-4]], amplitude=0.5,
                                   duration=4.0, quiet=1.0, rate=20.0, attitude_bound=None,
                                   restarts=2, iterations=100, switch_rate=5.0)
    # recomputed independently with fwid.simulate
    exp = fwid.Experiment(d.t, d.u, np.zeros(d.t.size), x0=np.zeros(1))
    ya = np.asarray(fwid.simulate(ma, exp)[1])
    yb = np.asarray(fwid.simulate(mb, exp)[1])
    assert d.distance == pytest.approx(np.sum((ya - yb) ** 2) / 1e-4, rel=1e-9)
    assert d.distance > d.distance_3211
    assert np.max(np.abs(d.u)) <= 0.5 + 1e-12 and np.all(d.u[d.t <= 1.0] == 0)
    # models differing in the gain alone: the best input holds the output up, the most
    # energy the low-pass passes: one sign for most of the window
    assert abs(np.mean(np.sign(d.u[d.t > 1.0]))) > 0.6


def test_a_model_that_diverges_for_the_3211_gets_a_faster_reference_or_a_smaller_one():
    # x' = -x + c x^2 + u has no equilibrium for u > 1/(4c) (finite escape): a slow 3211
    # diverges in model a; the reference is the first 3211 whose prediction stays finite
    # (filling the window, faster, then at half the amplitude), the design made from it
    # (before: "diverge for every input tried", or a design compared with a diverged 3211)
    def f(x, u, p, c):
        return jnp.stack([-x[0] + p["c"] * x[0] ** 2 + u[0]])
    mb = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"c": 0.0})
    t = np.arange(81) / 10.0

    def response(model, u):
        exp = fwid.Experiment(t, u, np.zeros(t.size), x0=np.zeros(1))
        return np.asarray(fwid.simulate(model, exp)[1])
    grid = fwid.design._signals.Grid(8.0, 1.0, 10.0)
    for c, kept in ((1.0, True), (4.0, False)):
        ma = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"c": c})
        d = fwid.design_discriminating(ma, mb, consts={}, R=[[1e-4]], amplitude=1.0,
                                       duration=8.0, quiet=1.0, rate=10.0,
                                       attitude_bound=None, restarts=2, iterations=30,
                                       switch_rate=2.0)
        used, unit = d.limits["amplitude_used_rad"], d.limits["reference_3211_unit_s"]
        assert (used == 1.0) == kept
        slower = [u for u in (1.0, 0.5) if u > unit]  # T/7, T/14 (T/28 < a step)
        ref = fwid.design._signals.input_3211(grid, used, unit)
        assert np.all(np.isfinite(response(ma, ref)))
        for u in slower:  # the slower ones at that amplitude diverge ...
            assert not np.all(np.isfinite(response(ma, fwid.design._signals.input_3211(
                grid, used, u))))
        if not kept:  # ... and every one at twice the amplitude
            for u in (1.0, 0.5):
                assert not np.all(np.isfinite(response(ma, fwid.design._signals.input_3211(
                    grid, 2 * used, u))))
        assert np.max(np.abs(d.u)) <= used + 1e-12
        ya, yb = response(ma, d.u), response(mb, d.u)
        assert np.all(np.isfinite(ya))
        assert d.distance == pytest.approx(np.sum((ya - yb) ** 2) / 1e-4, rel=1e-9)
        if np.isfinite(d.distance_3211):
            assert d.distance >= d.distance_3211 > 0
        else:
            assert d.to_json()["criterion"]["ratio"] is None


def test_the_loads_criterion_compares_the_loads_along_either_trajectory():
    # loads L = a x + b u: the models differ in the gain b; the criterion is half the sum over
    # both predicted trajectories of the squared load difference (mean removed) over S^2
    ma, mb = _first_order(1.0), _first_order(1.2)

    def loads_of(m):
        return lambda t, u, y: (m.params["a"] * y[:, 0] + m.params["b"] * u)[:, None]
    la, lb = loads_of(ma), loads_of(mb)
    d = fwid.design_discriminating(ma, mb, consts={}, R=[[1e-4]], amplitude=0.5,
                                   duration=4.0, quiet=1.0, rate=20.0, attitude_bound=None,
                                   restarts=2, iterations=60, switch_rate=5.0,
                                   loads_a=la, loads_b=lb, load_scale=[0.1])
    exp = fwid.Experiment(d.t, d.u, np.zeros(d.t.size), x0=np.zeros(1))
    ya = np.asarray(fwid.simulate(ma, exp)[1])[:, 0]
    yb = np.asarray(fwid.simulate(mb, exp)[1])[:, 0]
    want = 0.0
    for y in (ya, yb):  # L_a - L_b = (b_a - b_b) u on any trajectory (same a)
        diff = (-2.0 * y + 1.0 * d.u) - (-2.0 * y + 1.2 * d.u)
        want += 0.5 * np.sum(((diff - diff.mean()) / 0.1) ** 2)
    assert d.distance == pytest.approx(want, rel=1e-9)
    assert d.to_json()["criterion"]["name"].startswith("expected difference of the two "
                                                       "models' predicted loads")
    # the load difference is 0.2 u, mean removed: the best input swings between the limits
    assert d.distance >= d.distance_3211 > 0
    assert np.mean(np.abs(d.u[d.t > 1.0])) > 0.8 * 0.5


def test_a_classic_input_that_tells_them_apart_better_is_chosen():
    """Models differing only in the lag of the control (a servo): with the optimisation cut
    to one step of a random multisine, a classic input wins; the input returned is that
    signal and its D the largest scored."""
    def lagged(tau):
        def f(x, u, p, c):
            return jnp.stack([-2.0 * x[0] + x[1], (u[0] - x[1]) / p["tau"]])
        return fwid.GreyBoxModel(f, states=("x", "s"), inputs=("u",), params={"tau": tau})

    ma, mb = lagged(0.02), lagged(0.15)
    d = fwid.design_discriminating(ma, mb, consts={}, R=np.diag([1e-4, 1e-4]), amplitude=0.3,
                                   duration=4.0, quiet=1.0, rate=50.0, attitude_bound=None,
                                   restarts=1, iterations=1, parametrisation="multisine")
    alt = d.to_json()["criterion"]["alternatives"]
    assert set(alt) == {"optimised", "3211", "3211 half amplitude", "fast 3211", "fast doublet"}
    chosen = d.settings["chosen"]
    assert d.distance == pytest.approx(max(v for v in alt.values() if v is not None))
    assert alt[chosen] == pytest.approx(d.distance)
    assert chosen != "optimised" and alt["optimised"] < d.distance
    # linear models: half the amplitude, a quarter of D
    assert alt["3211 half amplitude"] == pytest.approx(alt["3211"] / 4, rel=1e-6)
    from fwid.design._discriminate import alternatives
    from fwid.design._signals import Grid

    np.testing.assert_allclose(d.u, alternatives(Grid(4.0, 1.0, 50.0), 0.3)[chosen])
