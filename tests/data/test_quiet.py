"""A flight with no quiet start: the trim needs at least 0.2 s of steady flight before the
first input; shorter, reading the flight warns in one line how long it was, how long it
must be, what the trim was taken from, and how to give the trim instead."""

import warnings

import numpy as np
import pytest

from fwid.data import read_flights
from fwid.data._quiet import quiet_start, quiet_start_note

from .helpers import lon_flight, write_flight


@pytest.mark.parametrize("shape", ["doublet", "211"])
@pytest.mark.parametrize("t_input", [0.03, 0.05, 0.1, 0.15])
def test_a_manoeuvre_early_in_the_flight_is_seen(t_input, shape):
    c = lon_flight(t_input=t_input, shape=shape)
    assert quiet_start(c["t"], c["de"]) < 0.2


@pytest.mark.parametrize("t_input", [0.3, 1.0, 2.0])
def test_a_quiet_start_is_quiet(t_input):
    c = lon_flight(t_input=t_input)
    assert quiet_start(c["t"], c["de"]) >= 0.2
    assert quiet_start_note("x.csv", c["t"], c, "de", None, "x.json") is None


def test_no_quiet_start_warns(tmp_path):
    path = write_flight(tmp_path, cols=lon_flight(t_input=0.05))
    with pytest.warns(UserWarning) as rec:
        record = read_flights(path)[0]
    msg = str(rec[0].message)
    assert record.warnings == (msg,) and "\n" not in msg
    assert msg.startswith(f"{path}: no quiet start: the input 'de' moves 0.0")
    assert "at least 0.2 s (40 samples)" in msg and "the trim was taken from the first" in msg
    assert f'give the trim in {path.with_suffix(".json")}: {{"trim": {{"u0": ..' in msg


def test_a_given_trim_silences_it(tmp_path):
    path = write_flight(tmp_path, cols=lon_flight(t_input=0.05),
                        sidecar={"trim": {"u0": 0.6, "w0": 0.25, "theta0": 1.25}})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        record = read_flights(path)[0]
    assert record.warnings == () and record.trim["u0"] == 0.6


def test_an_input_that_never_moves_is_quiet():
    t = np.arange(400) * 0.005
    assert quiet_start(t, np.full(t.shape, 0.05)) == pytest.approx(t[-1])
