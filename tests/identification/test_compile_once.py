"""Compiled once: a second identical `fwid.identify` in the same process compiles nothing
(no eager op-by-op JAX left on the path that recompiles), and the least-squares start is a
compiled function (it used to run op by op)."""

import logging

import jax
import pytest

import fwid
from fwid.synth import write_flights


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    folder = tmp_path_factory.mktemp("flights")
    # a length no other test uses, so the first call below compiles even late in the suite
    write_flights(folder, n_flights=3, axis="lon", seed=5, duration=3.715)
    return fwid.load_flights(folder)


def _compiles(caplog, run):
    """How many XLA compilations `run()` triggers (JAX logs each under `jax_log_compiles`)."""
    caplog.clear()
    with caplog.at_level(logging.WARNING), jax.log_compiles(True):
        run()
    return [r.getMessage() for r in caplog.records if "Compiling" in r.getMessage()]


def test_second_identify_compiles_nothing(flights, caplog):
    def run():
        return fwid.identify(flights[:2], "lon", validate=flights[2:])

    first = _compiles(caplog, run)
    assert first  # the first call did compile (the probe works)
    assert _compiles(caplog, run) == []


def test_start_compiles_once_for_flights_of_one_length(flights, caplog):
    model = fwid.longitudinal()
    exps = [fwid.experiment(fwid.cycle_averaged(f), model) for f in flights]
    fwid.least_squares_start(model, exps[:1])
    assert _compiles(caplog, lambda: [fwid.least_squares_start(model, [e]) for e in exps]) == []


@pytest.fixture(scope="module")
def other_length(tmp_path_factory):
    folder = tmp_path_factory.mktemp("other_length")
    # 3.6 s: another length, in the same padded length as the 3.715 s flights above
    write_flights(folder, n_flights=3, axis="lon", seed=6, duration=3.6)
    return fwid.load_flights(folder)


def test_new_length_in_a_bucket_compiles_no_estimator(flights, other_length, caplog):
    """Flights of a new length, padded to the length of the flights before: the start, the
    estimator and the simulation of the validation flight are not compiled again (only
    small programs for the data, e.g. the filters, are)."""
    from fwid.simulation import averaged, bucket_length

    def run(fl):
        return lambda: fwid.identify(fl[:2], "lon", validate=fl[2:])

    a, b = (averaged(f[0], fwid.longitudinal()).n for f in (flights, other_length))
    assert a != b and bucket_length(a) == bucket_length(b)
    _compiles(caplog, run(flights))
    heavy = ("_fit_each_batched", "_start_batch", "_force_dependence", "_solve_at_samples")
    again = _compiles(caplog, run(other_length))
    assert not [m for m in again if any(h in m for h in heavy)], again
