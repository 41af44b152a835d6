"""The time base of a flight file: in seconds (milliseconds, microseconds and nanoseconds
named, with the factor), uniform up to jitter (resampled with a warning within 25 % of the
step, refused beyond it)."""

import warnings

import numpy as np
import pytest

from fwid import FlightDataError
from fwid.data import load_flight, read_flights
from fwid.data._checks import check_time_unit
from fwid.data._timebase import JITTER, uniform_flight

from .helpers import lon_flight, write_flight


@pytest.mark.parametrize("scale, unit, factor", [(1e3, "milliseconds", "1000"),
                                                 (1e6, "microseconds", "1000000"),
                                                 (1e9, "nanoseconds", "1000000000")])
def test_time_not_in_seconds_is_named(tmp_path, scale, unit, factor):
    c = lon_flight()
    c["t"] = c["t"] * scale
    path = write_flight(tmp_path, cols=c)
    with pytest.raises(FlightDataError) as info:
        read_flights(path)
    msg = str(info.value)
    assert msg.startswith(str(path)) and "\n" not in msg
    assert f"t looks like {unit}" in msg and f"divide t by {factor}" in msg


def test_time_unit_from_the_flapping_frequency():
    """A short flight in ms at 2 kHz: step and duration pass as seconds, the wings do not."""
    t = np.arange(3000) * 0.5  # 1.5 s at 2 kHz, in ms: a 0.5 s step over 1500 s
    with pytest.raises(FlightDataError, match=r"milliseconds.*f = 12 Hz.*divide t by 1000"):
        check_time_unit("x.csv", t, np.full(t.shape, 12.0))


@pytest.mark.parametrize("dt, f", [(0.005, 12.0), (0.05, 12.0), (0.001, None), (0.1, 20.0)])
def test_time_in_seconds_passes(dt, f):
    t = 3.0 + np.arange(600) * dt
    check_time_unit("x.csv", t, None if f is None else np.full(t.shape, f))


def test_jitter_is_resampled_with_a_warning(tmp_path):
    c = lon_flight()
    rng = np.random.default_rng(0)
    c["t"] = c["t"] + rng.uniform(-0.02, 0.02, c["t"].shape) * 0.005  # 4 % of the step
    path = write_flight(tmp_path, cols=c)
    with pytest.warns(UserWarning, match=r"lon_0\.csv: the time stamps jitter by up to 3.\d% "
                                         r"of the step.*resampled onto a uniform") as rec:
        flight = load_flight(path)
    assert "25%" in str(rec[0].message)
    d = np.diff(np.asarray(flight.t))
    assert np.allclose(d, d[0]) and abs(d[0] - 0.005) < 1e-4
    # the samples moved onto the grid: the ripple's phase follows the true times
    assert np.max(np.abs(np.asarray(flight["f"]) - np.interp(flight.t, c["t"], c["f"]))) < 1e-6
    with pytest.warns(UserWarning):
        assert read_flights(path)[0].warnings == (str(rec[0].message),)


def test_uniform_flight_keeps_a_uniform_one():
    t = np.arange(100) * 0.01
    grid, cols, note = uniform_flight("x.csv", t + 1e-7, {"u": t})
    assert note is None and cols["u"] is not None and np.allclose(np.diff(grid), 0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        uniform_flight("x.csv", t, {"u": t})


def test_jitter_beyond_the_limit_is_refused(tmp_path):
    c = lon_flight()
    c["t"][200:] += (JITTER + 0.05) * 0.005
    with pytest.raises(FlightDataError, match=r"not uniformly sampled.*off by more than 25%"):
        load_flight(write_flight(tmp_path, cols=c))


def test_reconstruction_uses_the_same_time_base():
    """One piece of code for one piece of logic: the raw recordings' time base is this one."""
    from fwid.data import _timebase
    from fwid.reconstruction import _mapped

    assert _mapped.uniform_time is _timebase.uniform_time
    assert _mapped.onto_grid is _timebase.onto_grid


def test_an_uneven_logger_is_resampled_and_its_long_steps_are_dropouts():
    """A raw recording from a logger whose loop runs unevenly (steps 70-130 % of the typical
    one) is resampled, not refused; a step over `GAP` typical ones holds missing samples."""
    from fwid.data._timebase import GAP, onto_grid, uniform_time

    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.7, 1.3, 400) * 0.01)
    t = np.concatenate([t[:200], t[200:] + 0.05])  # 50 ms lost after row 200
    grid, how, notes = uniform_time(t, "log.mat", 1)
    x = onto_grid(np.sin(t), how)
    inside = (grid > t[199] + 1e-9) & (grid < t[200] - 1e-9)
    assert inside.sum() >= 4 and np.all(np.isnan(x[inside]))
    assert np.max(np.abs(x[~inside] - np.sin(grid[~inside]))) < 1e-3
    assert any("jitter by up to" in n for n in notes)
    assert any(f"over {GAP:g} times" in n and "dropouts" in n for n in notes)
    with pytest.raises(FlightDataError, match="does not increase"):
        uniform_time(np.array([0.0, 0.01, 0.01, 0.02]), "log.mat", 1)
