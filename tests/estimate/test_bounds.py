"""Bounds on parameters: the bounded-variable Gauss-Newton step of the output-error fit."""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.estimate._gauss_newton import bounded_newton


def test_active_bound_holds_and_is_reported(short_period):
    """The ML estimate of Mq is -2.53; with Mq >= -2.3 the estimate sits at -2.3, the bound
    is reported active, Mq's std is NaN, and the others are those of the fit with Mq fixed
    at -2.3: the same estimates and (conditional) standard deviations."""
    sp = short_period
    assert sp.at(sp.plain, "Mq") < -2.4
    r = fwid.fit(sp.model, sp.exps[0], bounds={"Mq": (-2.3, None)})
    assert sp.at(r, "Mq") == -2.3
    assert r.active_bounds == {"Mq": "low"}
    assert r.bounds_table() == {"Mq": {"low": -2.3, "high": None, "active": True, "at": "low"}}
    i = r.names.index("Mq")
    assert np.isnan(float(r.std[i])) and np.isnan(float(r.std_cr[i]))
    assert bool(r.converged) and not r.warnings
    for k in sp.held_mq.names:
        assert sp.at(r, k) == pytest.approx(sp.at(sp.held_mq, k), rel=1e-7, abs=1e-12)
        assert sp.std_cr(r, k) == pytest.approx(sp.std_cr(sp.held_mq, k), rel=1e-6)


def test_upper_bound_and_two_at_once(short_period):
    sp = short_period
    ma, mde = sp.at(sp.plain, "Ma"), sp.at(sp.plain, "Mde")
    r = fwid.fit(sp.model, sp.exps[0],
                 bounds={"Ma": {"high": ma + 0.3}, "Mde": {"low": mde + 0.5, "high": 0.0},
                         "Za": (-100.0, 100.0)})
    theta = {k: sp.at(r, k) for k in r.names}
    assert theta["Ma"] <= ma + 0.3 and mde + 0.5 <= theta["Mde"] <= 0.0
    assert r.active_bounds.get("Mde") == "low"  # the data pull Mde well below the bound
    assert "Za" not in r.active_bounds
    for k in r.names:
        lo, hi = {"Ma": (-np.inf, ma + 0.3), "Mde": (mde + 0.5, 0.0)}.get(k, (-np.inf, np.inf))
        side = r.active_bounds.get(k)
        assert (side == "low") == (theta[k] == lo) and (side == "high") == (theta[k] == hi)


def test_inactive_bound_changes_nothing(short_period):
    sp = short_period
    r = fwid.fit(sp.model, sp.exps[0], bounds={"Mq": (-10.0, 0.0), "Ma": (None, 0.0)})
    np.testing.assert_allclose(np.asarray(r.theta), np.asarray(sp.plain.theta), rtol=1e-9,
                               atol=1e-12)
    np.testing.assert_allclose(np.asarray(r.std), np.asarray(sp.plain.std), rtol=1e-9)
    assert r.active_bounds == {} and int(r.steps) == int(sp.plain.steps)


def test_start_is_clipped_into_the_bounds(short_period):
    """A start outside the bounds (Mq = -2.0 above the upper bound -2.4) is clipped onto it;
    the estimate (inside) is the plain one."""
    sp = short_period
    r = fwid.fit(sp.model, sp.exps[0], start="model", bounds={"Mq": (-3.0, -2.4)})
    assert float(r.start[r.names.index("Mq")]) == -2.4
    np.testing.assert_allclose(np.asarray(r.theta), np.asarray(sp.plain.theta), rtol=1e-7,
                               atol=1e-10)
    assert r.active_bounds == {}


def test_fit_each_keeps_the_bounds_per_flight(short_period):
    """Every flight's fit in the batched call is the fit of that flight alone."""
    sp = short_period
    bounds = {"Mq": (-2.3, None)}
    each = fwid.fit_each(sp.model, sp.exps, bounds=bounds)
    for e, r in zip(sp.exps, each):
        alone = fwid.fit(sp.model, e, bounds=bounds)
        np.testing.assert_allclose(np.asarray(r.theta), np.asarray(alone.theta), rtol=1e-9)
        assert r.active_bounds == alone.active_bounds == {"Mq": "low"}


def test_bounded_step_against_the_reduced_normal_equations():
    """The bounded-variable step: a parameter at its bound whose Newton step points out is
    held (step 0) and the step of the others solves their own normal equations; one whose
    step points in is free. Compared with numpy's solve of the reduced system."""
    rng = np.random.default_rng(1)
    A = rng.normal(size=(20, 4))
    H = A.T @ A
    g = rng.normal(size=4)
    y = np.zeros(4)
    free = np.linalg.solve(H, g)
    n, held = bounded_newton(jnp.asarray(H), jnp.asarray(g), jnp.asarray(y),
                             -jnp.full(4, jnp.inf), jnp.full(4, jnp.inf))
    np.testing.assert_allclose(np.asarray(n), free, rtol=1e-12)
    assert not np.any(np.asarray(held))

    def at_zero(side):  # parameter 0 at a bound 0 on `side`, the others open
        lo, hi = np.full(4, -np.inf), np.full(4, np.inf)
        (lo if side == "low" else hi)[0] = 0.0
        return jnp.asarray(lo), jnp.asarray(hi)

    out = "low" if free[0] > 0 else "high"  # the step, -newton, goes down / up
    n, held = bounded_newton(jnp.asarray(H), jnp.asarray(g), jnp.asarray(y), *at_zero(out))
    reduced = np.linalg.solve(H[1:, 1:], g[1:])
    np.testing.assert_allclose(np.asarray(n), np.r_[0.0, reduced], rtol=1e-10, atol=1e-14)
    assert int(np.asarray(held)[0]) == (-1 if out == "low" else 1)
    assert not np.any(np.asarray(held)[1:])
    # at the bound on the other side its step points in: free, the plain step
    n, held = bounded_newton(jnp.asarray(H), jnp.asarray(g), jnp.asarray(y),
                             *at_zero("high" if out == "low" else "low"))
    np.testing.assert_allclose(np.asarray(n), free, rtol=1e-12)
    assert not np.any(np.asarray(held))


@pytest.mark.parametrize("bounds, words", [
    ({"Mq": (0.0, -1.0)}, ["'Mq'", "low 0 >= high -1", "low < high"]),
    ({"Mq": (1.0, 1.0)}, ["'Mq'", ">="]),
    ({"Mx": (None, 1.0)}, ["'Mx'", "not a free parameter", "Za", "Mde"]),
    ({"Mq": ("a", 1.0)}, ["'Mq'", "low", "finite number"]),
    ({"Mq": {"lo": 1.0}}, ["'Mq'", "'lo'"]),
    ({"Mq": 3.0}, ["'Mq'", "(low, high)"]),
])
def test_bad_bounds_are_one_line_input_errors(short_period, bounds, words):
    with pytest.raises(fwid.InputError) as err:
        fwid.fit(short_period.model, short_period.exps[0], bounds=bounds)
    msg = str(err.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_bound_on_a_fixed_parameter_is_refused(short_period):
    model = short_period.model.with_free([k for k in short_period.model.free if k != "Mq"])
    with pytest.raises(fwid.InputError, match="'Mq' is not a free parameter"):
        fwid.fit(model, short_period.exps[0], bounds={"Mq": (-3.0, 0.0)})
