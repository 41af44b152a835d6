"""`--window START:END` on `fwid identify` and `fwid diagnose`: seconds on each flight's own
`t`, the trim found on what is kept; malformed text and windows that leave too little exit 2
with one line."""

import json

import numpy as np
import pytest

from fwid import FlightDataError, InputError
from fwid.cli import main
from fwid.data import estimate_trim, read_flights
from fwid.data._window import parse_window
from fwid.synth import write_flights


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    out = tmp_path_factory.mktemp("window")
    write_flights(out, n_flights=1, seed=5, duration=6.0)
    return out / "lon_0.csv"


@pytest.mark.parametrize("text, want", [("5:20", (5.0, 20.0)), ("5:", (5.0, None)),
                                        (":20", (None, 20.0)), ("-1.5:2e1", (-1.5, 20.0)),
                                        (" 0.5 : 3 ", (0.5, 3.0))])
def test_window_parses(text, want):
    assert parse_window(text) == want


@pytest.mark.parametrize("text", ["5-20", "a:b", "20:5", "5:5", ":", "", "1:2:3", "nan:4"])
def test_malformed_window_is_one_line_with_the_form(text):
    with pytest.raises(InputError) as e:
        parse_window(text)
    assert "START:END" in str(e.value) and "e.g. --window 12.5:40" in str(e.value)


def test_window_cuts_the_flight_and_the_trim_comes_from_its_start(flight, tmp_path):
    (tmp_path / flight.name).write_text(flight.read_text())  # no sidecar: the trim estimated
    flight = tmp_path / flight.name
    (whole,) = read_flights(flight)
    with pytest.warns(UserWarning, match="no quiet start: the input 'de' moves 0 s in"):
        (cut,) = read_flights(flight, window=(2.0, 5.0))  # mid-manoeuvre: said
    assert cut.t[0] == pytest.approx(2.0) and cut.t[-1] == pytest.approx(5.0)
    assert np.array_equal(cut.columns["q"], whole.columns["q"][(whole.t >= 2 - 1e-9)
                                                                 & (whole.t <= 5 + 1e-9)])
    assert cut.trim["u0"] != pytest.approx(whole.trim["u0"], abs=1e-6)
    assert cut.trim == pytest.approx(estimate_trim(cut.columns, cut.t, first_input=cut.first))
    (tail,) = read_flights(flight, window=(3.0, None))
    assert tail.t[0] == pytest.approx(3.0) and tail.t[-1] == whole.t[-1]


@pytest.mark.parametrize("window, said", [((10.0, 20.0), "leaves none of it"),
                                          ((5.0, None), "leaves 1 s of it")])
def test_a_window_that_leaves_too_little_names_the_flight_and_its_span(flight, window, said):
    with pytest.raises(FlightDataError) as e:
        read_flights(flight, window=window)
    msg = str(e.value)
    assert msg.startswith(str(flight)) and said in msg
    assert "runs from t = 0 to 6 s" in msg and "at least 2 s" in msg and "\n" not in msg


@pytest.mark.parametrize("args", [["--window", "5-20"], ["--window", "a:b"],
                                  ["--window", "4:2"], ["--window", "30:40"]])
def test_bad_windows_exit_2_with_one_line(flight, capsys, args):
    for cmd in (["identify", str(flight), "--model", "lon"],
                ["diagnose", "--train", str(flight), "--test", str(flight)]):
        assert main([*cmd, *args]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--window" in err[0], err


def test_identify_with_a_window_writes_it_in_the_report(flight, tmp_path):
    out = tmp_path / "report"
    assert main(["identify", str(flight), "--model", "lon", "--window", "0.5:5.5", "--out",
                 str(out), "--quiet", "--figures", "none"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["window"] == [0.5, 5.5]
