"""The least-squares start of every flight in one batched, compiled call: the
start values of `least_squares_start` on each flight alone, to 1e-9, whatever the flights'
lengths (padding) and whether they carry the forces, compiled once for the batch."""

import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.estimate import least_squares_start
from fwid.estimate._start_each import least_squares_start_each
from fwid.models import lateral, longitudinal
from fwid.simulation import Experiment


def _noisy(flight, seed, n, forces=True):
    """The first `n` samples of `flight` with white noise on the outputs and the forces."""
    rng = np.random.default_rng(seed)
    z = flight.ys[:n] + 0.02 * flight.ys.std(axis=0) * rng.standard_normal((n, flight.ys.shape[1]))
    f = flight.forces[:n] * (1 + 0.01 * rng.standard_normal((n, flight.forces.shape[1])))
    return Experiment(flight.t[:n], flight.u[:n], z, flight.x0, flight.consts,
                      forces=f if forces else None)


@pytest.mark.parametrize("kind", ["lon", "lat"])
def test_batched_start_equals_each_flight_alone(kind, lon_flight, lat_flight):
    flight, family = (lon_flight, longitudinal) if kind == "lon" else (lat_flight, lateral)
    # two lengths (the shorter padded), and one flight without forces (regressed on the
    # differentiated states alone, in a batch of its own)
    exps = [_noisy(flight, 1, 901), _noisy(flight, 2, 640), _noisy(flight, 3, 901, False)]
    model = family()
    batched = least_squares_start_each(model, exps)
    for e, b in zip(exps, batched):
        a = least_squares_start(model, [e])
        for k in model.free:
            assert float(b.params[k]) == pytest.approx(float(a.params[k]), rel=1e-9, abs=1e-300), k
    # a start that did something: far from the nominal values
    assert not np.allclose(np.asarray(batched[0].theta()), np.asarray(model.theta()), rtol=0.05)


def test_one_compilation_for_all_flights(lon_flight, caplog):
    """A second batch of other flights of the same shape compiles nothing."""
    import logging

    import jax

    least_squares_start_each(longitudinal(), [_noisy(lon_flight, s, 901) for s in (4, 5, 6)])
    with caplog.at_level(logging.WARNING), jax.log_compiles(True):
        least_squares_start_each(longitudinal(), [_noisy(lon_flight, s, 901) for s in (7, 8, 9)])
    assert not [r for r in caplog.records if "Compiling" in r.getMessage()]


def test_fit_on_a_padded_flight_is_unchanged(lon_flight, monkeypatch):
    """`fwid.fit` pads the flight to its bucket length (masked): the estimates, their
    standard deviations and the steps equal those on the flight as it is (1e-9)."""
    import importlib

    oe = importlib.import_module("fwid.estimate._output_error")
    exp = _noisy(lon_flight, 11, 901, forces=False)  # padded to 960, as in the other tests
    padded = fwid.fit(longitudinal(), exp, noise="full")
    monkeypatch.setattr(oe, "bucket_length", lambda n: n)
    plain = fwid.fit(longitudinal(), exp, noise="full")
    np.testing.assert_allclose(np.asarray(padded.theta), np.asarray(plain.theta), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(padded.std), np.asarray(plain.std), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(padded.R), np.asarray(plain.R), rtol=1e-9)
    assert int(padded.steps) == int(plain.steps)
