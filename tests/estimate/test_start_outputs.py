"""Start values for a model with an output equation h whose states are measured
(fwid/estimate/_start_outputs.py), and x0 from the first measured sample of the states."""

import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.simulation._experiment import with_measured_x0

T = np.arange(500) * 0.02
DE = 0.05 * np.sin(1.3 * T) + 0.03 * np.sin(3.7 * T)
TRUE = dict(Zw=-1.4, Zde=-6.0, Mw=-0.2, Mq=-3.5, Mde=-12.0)
U0 = 20.0


def _short_period(**params):
    """Short period in w, q with the output az = Zw w + Zde de (FVSysID TC08's form)."""
    def f(x, u, p, c):
        return jnp.stack([p["Zw"] * x[0] + U0 * x[1] + p["Zde"] * u[0],
                          p["Mw"] * x[0] + p["Mq"] * x[1] + p["Mde"] * u[0]])

    def h(x, u, p, c):
        return jnp.stack([p["Zw"] * x[0] + p["Zde"] * u[0], x[0], x[1]])

    start = dict(Zw=-0.5, Zde=-1.0, Mw=-0.05, Mq=-1.0, Mde=-3.0, unused=1.0)
    start.update(params)
    return fwid.GreyBoxModel(f, states=("w", "q"), inputs=("de",), h=h,
                             outputs=("az", "w", "q"), params=start, name="sp")


def _data(noise=0.0, seed=0):
    x0 = np.array([0.1, -0.01])
    _, y = fwid.simulate(_short_period(**TRUE), fwid.Experiment(T, DE, np.zeros((T.size, 3)),
                                                                 x0=x0))
    rng = np.random.default_rng(seed)
    return np.asarray(y) + noise * rng.standard_normal(y.shape) * np.array([0.05, 0.01, 0.001])


def test_equation_error_start_equals_the_independent_regression():
    """Linear in the parameters: one least-squares solve, equal to numpy's regression of the
    differentiated measured w, q and the measured az on the measured w, q, de (each channel
    scaled by its standard deviation, as fwid does). Noise-free data give the true values."""
    z = _data(noise=1.0)
    e = fwid.Experiment(T, DE, z)  # no x0: the first measured w, q
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        start = fwid.least_squares_start(_short_period(), [e])
    kept = [str(m.message) for m in caught]
    assert len(kept) == 1 and "keeps the nominal values of unused" in kept[0]
    assert "neither f nor h depends on them" in kept[0]
    # independent: stack the three scaled equations and solve for [Zw, Zde, Mw, Mq, Mde]
    w, q = z[:, 1], z[:, 2]
    wd, qd = np.gradient(w, T), np.gradient(q, T)
    sw, sq, saz = wd.std(), qd.std(), z.std(axis=0)
    zero = np.zeros_like(w)
    A = np.concatenate([
        np.column_stack([w, DE, zero, zero, zero]) / sw,
        np.column_stack([zero, zero, w, q, DE]) / sq,
        np.column_stack([w, DE, zero, zero, zero]) / saz[0],
    ])
    b = np.concatenate([(wd - U0 * q) / sw, qd / sq, z[:, 0] / saz[0]])
    ref, *_ = np.linalg.lstsq(A, b, rcond=None)
    got = [float(start.params[k]) for k in ("Zw", "Zde", "Mw", "Mq", "Mde")]
    np.testing.assert_allclose(got, ref, rtol=1e-9)
    clean = fwid.least_squares_start(_short_period(),
                                     [fwid.Experiment(T, DE, _data(noise=0.0))]).params
    for k, v in TRUE.items():  # only the numerical derivative's error is left
        assert abs(float(clean[k]) - v) < 0.02 * abs(v), (k, float(clean[k]))


def test_missing_x0_is_the_first_sample_of_the_measured_states_and_the_fit_recovers():
    z = _data(noise=0.2, seed=1)
    model = _short_period().with_free(["Zw", "Zde", "Mw", "Mq", "Mde"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", fwid.FitWarning)  # a good start, a clean fit
        r = fwid.fit(model, fwid.Experiment(T, DE, z), names=["sp0"])
    assert bool(r.converged)
    for k, v in TRUE.items():
        assert abs(float(r.params[k]) - v) < 4 * float(r.std[r.names.index(k)]) + 1e-9, k
    exp = with_measured_x0(model, fwid.Experiment(T, DE, z))
    np.testing.assert_array_equal(np.asarray(exp.x0), z[0, 1:])


def test_states_not_all_measured_still_ask_for_x0():
    def h(x, u, p, c):
        return jnp.stack([p["Zw"] * x[0] + p["Zde"] * u[0], x[0]])

    m = fwid.GreyBoxModel(_short_period().f, states=("w", "q"), inputs=("de",), h=h,
                          outputs=("az", "w"), params=dict(TRUE), name="sp2")
    with pytest.raises(fwid.InputError, match="no x0 was given"):
        fwid.fit(m, fwid.Experiment(T, DE, _data()[:, :2]), start="model")
