"""Padded lengths: a few lengths per octave, and padding that changes no result."""

import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.models import longitudinal
from fwid.simulation import Experiment, bucket_length, pad_experiment, simulate


def test_bucket_lengths_are_few_and_tight():
    ns = np.arange(1, 5000)
    b = np.array([bucket_length(n) for n in ns])
    assert np.all(b >= ns) and np.all(np.diff(b) >= 0)
    assert np.all(b[ns > 64] <= 1.125 * ns[ns > 64])  # at most 12.5 % padding
    for k in range(7, 12):  # eight lengths per octave
        assert len(set(b[(ns > 2**k) & (ns <= 2**(k + 1))])) == 8
    assert bucket_length(901) == bucket_length(950) == 960  # 4.5 s and 4.75 s at 200 Hz


def test_padding_is_masked_and_simulates_the_same():
    n = 901
    t = np.arange(n) * 0.005
    rng = np.random.default_rng(0)
    u = 0.05 * np.sin(2 * np.pi * 0.7 * t)
    exp = Experiment(t, u, rng.normal(size=(n, 4)), np.array([0.1, 0.0, 0.0, 0.0]),
                     dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2),
                     forces=rng.normal(size=(n, 3)))
    p = pad_experiment(exp)
    assert p.n == 960 and float(p.mask.sum()) == n and np.all(np.asarray(p.mask[n:]) == 0)
    np.testing.assert_array_equal(np.asarray(p.u[n:]), np.repeat(np.asarray(exp.u[-1:]), 59, 0))
    np.testing.assert_allclose(np.diff(np.asarray(p.t)), 0.005, rtol=1e-9)
    assert p.forces.shape == (960, 3) and pad_experiment(p) is p
    xa, ya = simulate(longitudinal(), exp)
    xb, yb = simulate(longitudinal(), p)
    np.testing.assert_allclose(np.asarray(yb[:n]), np.asarray(ya), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("refit", [True, False])
def test_evaluate_on_a_padded_flight_is_unchanged(monkeypatch, refit):
    """`evaluate` simulates the flight padded to its bucket length: the scores and the
    re-estimated biases equal those on the flight as it is (1e-9)."""
    import importlib

    ff = importlib.import_module("fwid.identification._flight_fit")

    n = 880
    t = np.arange(n) * 0.005
    u = 0.05 * np.sign(np.sin(2 * np.pi * 0.6 * t))
    consts = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
    model = longitudinal().with_params(bq=0.01, bu=-0.005)
    _, y = simulate(model, Experiment(t, u, np.zeros((n, 4)), np.zeros(4), consts))
    z = np.asarray(y) + 1e-3 * np.random.default_rng(1).normal(size=(n, 4))
    exp = Experiment(t, u, z, np.zeros(4), consts)
    padded = ff.evaluate(longitudinal(), exp, "f", refit_local=refit)
    monkeypatch.setattr(ff, "pad_experiment", lambda e: e)
    plain = ff.evaluate(longitudinal(), exp, "f", refit_local=refit)
    for k, v in plain.local_params.items():
        assert padded.local_params[k] == pytest.approx(v, rel=1e-9, abs=1e-15)
    for k in plain.simulated:
        np.testing.assert_allclose(padded.simulated[k], plain.simulated[k], rtol=1e-9,
                                   atol=1e-15)
        for m, v in plain.metrics[k].items():
            assert padded.metrics[k][m] == pytest.approx(v, rel=1e-9), (k, m)
