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


def test_a_model_that_diverges_at_full_amplitude_gets_a_smaller_one():
    # x' = -x + x^2 + u has no equilibrium for u > 1/4 (finite escape, after 2.4 s at
    # u = 1): the 3211 of 1 rad diverges in model a; the amplitude is halved until it
    # does not, and the design is made there (before: "diverge for every input tried")
    def f(x, u, p, c):
        return jnp.stack([-x[0] + p["c"] * x[0] ** 2 + u[0]])
    ma = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"c": 1.0})
    mb = fwid.GreyBoxModel(f, states=("x",), inputs=("u",), params={"c": 0.0})
    d = fwid.design_discriminating(ma, mb, consts={}, R=[[1e-4]], amplitude=1.0,
                                   duration=8.0, quiet=1.0, rate=10.0, attitude_bound=None,
                                   restarts=2, iterations=50, switch_rate=2.0)

    def response(model, u):
        exp = fwid.Experiment(d.t, u, np.zeros(d.t.size), x0=np.zeros(1))
        return np.asarray(fwid.simulate(model, exp)[1])
    assert np.isfinite(d.distance_3211) and d.distance >= d.distance_3211 > 0
    used = d.limits["amplitude_used_rad"]
    assert used < 1.0
    assert np.all(np.isfinite(response(ma, d.u_3211)))
    assert not np.all(np.isfinite(response(ma, 2 * d.u_3211)))  # the largest finite one
    assert np.max(np.abs(d.u)) <= used + 1e-12
    ya, yb = response(ma, d.u), response(mb, d.u)
    assert np.all(np.isfinite(ya))
    assert d.distance == pytest.approx(np.sum((ya - yb) ** 2) / 1e-4, rel=1e-9)
