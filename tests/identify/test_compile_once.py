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
