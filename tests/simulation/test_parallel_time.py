"""The parallel-in-time simulation (associative scan of RK4's affine steps) against the
sequential RK4 scan: states, outputs and forward sensitivities, and the affinity check."""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.models import GreyBoxModel, lateral, longitudinal
from fwid.simulation import Experiment, simulate
from fwid.simulation._parallel_time import affine_in_state, use_parallel
from fwid.simulation._simulate import simulate_sensitivities

LON = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
LAT = dict(mass=0.0205, Ix=4e-5, Iz=3e-5, Ixz=1e-6, g=9.81, u0=0.3, w0=0.6, theta0=1.2)


def _exp(n, consts, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.005
    u = 0.04 * np.sin(2 * np.pi * 1.1 * t) + 0.01 * rng.standard_normal(n)
    return Experiment(t, u, np.zeros((n, 4)), np.array([0.1, -0.05, 0.02, 0.03]), consts)


def _rel(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(np.asarray(b))))


@pytest.mark.parametrize("which, n", [("lon", 900), ("lon", 9000), ("lat", 900)])
def test_parallel_equals_sequential(which, n):
    model = longitudinal(dict(bq=0.02, bu=-0.01)) if which == "lon" else lateral(dict(bp=0.01))
    exp = _exp(n, LON if which == "lon" else LAT)
    th = jnp.asarray([model.params[k] for k in model.free])
    y_s, S_s = simulate_sensitivities(model, exp, model.merge, th, time_parallel=False)
    y_p, S_p = simulate_sensitivities(model, exp, model.merge, th, time_parallel=True)
    assert S_p.shape == S_s.shape == (n, 4, len(model.free))
    assert _rel(y_p, y_s) < 1e-12  # the outputs are the states
    # relative to each parameter's largest sensitivity (they span orders of magnitude)
    scale = np.max(np.abs(np.asarray(S_s)), axis=(0, 1))
    assert np.max(np.abs(np.asarray(S_p - S_s)) / scale) < 1e-12


def _nonlinear(x, u, p, c):
    return jnp.stack([x[1], -p["k"] * jnp.sin(x[0]) + u[0]])


def _bilinear(x, u, p, c):  # affine in the state for each input: A(u) x + b
    return jnp.stack([u[0] * x[1] + p["k"], -p["k"] * x[0] / c["m"] + jnp.cos(u[0])])


def _product(x, u, p, c):
    return jnp.stack([x[0] * x[1], p["k"] * x[0]])


def _branch(x, u, p, c):
    return jnp.where(x > 0, p["k"] * x, 0.0)


@pytest.mark.parametrize("f, affine", [(_nonlinear, False), (_bilinear, True),
                                       (_product, False), (_branch, False)])
def test_affinity_is_read_from_the_model(f, affine):
    x, u, args = jnp.zeros(2), jnp.zeros(1), (dict(k=1.0), dict(m=2.0))
    field = lambda x_, u_, a: f(x_, u_, *a)  # noqa: E731
    assert affine_in_state(field, x, u, args) is affine
    assert use_parallel(False, field, x, u, args) is False
    if not affine:
        with pytest.raises(ValueError, match="affine in its state"):
            use_parallel(True, field, x, u, args)
    with pytest.raises(ValueError, match="time_parallel must be"):
        use_parallel("yes", field, x, u, args)


def test_state_affine_model_with_input_dependent_matrix():
    model = GreyBoxModel(_bilinear, states=("a", "b"), inputs=("d",), params=dict(k=0.3),
                         constants=("m",))
    n = 900
    t = np.arange(n) * 0.01
    exp = Experiment(t, 0.5 * np.sin(t), np.zeros((n, 2)), np.array([0.2, -0.1]), dict(m=2.0))
    xs_s, _ = simulate(model, exp, time_parallel=False)
    xs_p, _ = simulate(model, exp, time_parallel=True)
    assert _rel(xs_p, xs_s) < 1e-12


def test_auto_keeps_the_sequential_path_on_cpu():
    model = longitudinal()
    exp = _exp(50, LON)
    xs_a, _ = simulate(model, exp)
    xs_s, _ = simulate(model, exp, time_parallel=False)
    np.testing.assert_array_equal(np.asarray(xs_a), np.asarray(xs_s))
