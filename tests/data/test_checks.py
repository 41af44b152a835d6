"""Every check of `fwid.data` raises a one-line `FlightDataError` that names the file,
the column / row, and says how to fix it."""


from pathlib import Path

import numpy as np
import pytest

from fwid import FlightDataError, InputError
from fwid.data import load_flight
from fwid.data._checks import (
    check_finite,
    check_flight,
    check_frequency,
    check_length,
    check_time,
    check_units,
    time_quantum,
)

from .helpers import lon_flight, write_csv, write_text


def _error(path, **kw) -> str:
    with pytest.raises(FlightDataError) as info:
        load_flight(path, **kw)
    msg = str(info.value)
    assert "\n" not in msg, "messages are one line"
    assert msg.startswith(path.name + ": ") or msg.startswith(str(path)), msg
    assert isinstance(info.value, InputError)
    return msg


def _edit_cell(path, row, col, value):
    """Replace the cell of data row `row` (0-based) in column `col` of a CSV."""
    lines = path.read_text().splitlines()
    j = lines[0].split(",").index(col)
    fields = lines[row + 1].split(",")
    fields[j] = value
    lines[row + 1] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")


# ------------------------------------------------------------------ columns


def test_missing_time_column(tmp_path):
    c = lon_flight()
    del c["t"]
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "missing time column 't'" in msg
    assert "add a time column 't'" in msg


def test_time_column_under_another_name(tmp_path):
    c = lon_flight()
    c = {"time": c.pop("t"), **c}
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "rename 'time' to 't'" in msg


def test_missing_required_column(tmp_path):
    path = write_csv(tmp_path / "lon_3.csv", lon_flight())
    msg = _error(path, require=("q", "p"))
    assert "missing column 'p' needed by this model" in msg
    assert "'q'" not in msg.split("(")[0]
    msg = _error(path, require=("p", "r"))
    assert "missing columns 'p', 'r'" in msg


# ------------------------------------------------------------------ parsing


def test_empty_file(tmp_path):
    msg = _error(write_text(tmp_path / "empty.csv", ""))
    assert "file is empty" in msg


def test_header_only(tmp_path):
    msg = _error(write_text(tmp_path / "hdr.csv", "t,q,u\n\n"))
    assert "no data rows" in msg


def test_no_header_row(tmp_path):
    msg = _error(write_text(tmp_path / "nohdr.csv", "0,0.1\n0.005,0.2\n"))
    assert "no column names" in msg and "add a header row" in msg


def test_not_comma_separated(tmp_path):
    msg = _error(write_text(tmp_path / "semi.csv", "t;q;u\n0;1;2\n"))
    assert "semicolons" in msg and "comma-separated" in msg


def test_non_numeric_cell(tmp_path):
    path = write_csv(tmp_path / "lon_0.csv", lon_flight())
    _edit_cell(path, 17, "q", "abc")
    msg = _error(path)
    assert "non-numeric value 'abc' in column 'q' at row 17 (line 19)" in msg


def test_non_numeric_extra_column_is_dropped_not_an_error(tmp_path):
    c = lon_flight()
    path = write_csv(tmp_path / "lon_0.csv", {**c, "label": np.zeros_like(c["t"])})
    _edit_cell(path, 3, "label", "gust")
    flight = load_flight(path)
    assert "label" not in flight.columns and "q" in flight.columns


def test_row_with_wrong_number_of_fields(tmp_path):
    path = write_csv(tmp_path / "lon_0.csv", lon_flight())
    lines = path.read_text().splitlines()
    lines[21] += ",5,6"
    path.write_text("\n".join(lines) + "\n")
    msg = _error(path)
    assert "line 22 has" in msg and "fields but the header has" in msg


def test_duplicate_column(tmp_path):
    msg = _error(write_text(tmp_path / "dup.csv", "t,q,q\n0,1,2\n"))
    assert "column 'q' appears twice" in msg


def test_not_a_file(tmp_path):
    msg = str(pytest.raises(FlightDataError, load_flight, tmp_path / "nope.csv").value)
    assert "nope.csv: no such file" in msg
    msg = str(pytest.raises(FlightDataError, load_flight, tmp_path).value)
    assert "is a folder" in msg


def test_binary_file(tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00\x81garbage")
    assert "not a text file" in _error(path)


# ------------------------------------------------------------------ NaN / inf


def test_nan_names_column_rows_and_time(tmp_path):
    c = lon_flight()
    c["q"][17:19] = np.nan
    path = write_csv(tmp_path / "lon_0.csv", c)
    msg = _error(path)
    assert msg == (
        f"{path}: column 'q' has NaN at lines 19, 20 (t=0.085 s); fill or cut these samples"
    )


def test_nan_lines_as_an_editor_shows_them(tmp_path):
    """Lines count from 1 with the header and the comment and blank lines above and between
    the samples, as an editor numbers them; every bad column is named at once."""
    c = lon_flight()
    c["q"][3] = np.nan
    c["w"][10] = np.nan
    path = write_csv(tmp_path / "lon_0.csv", c)
    lines = path.read_text().splitlines()
    lines[0:0] = ["# exported by the lab's logger", ""]  # header on line 3
    lines.insert(8, "")  # samples 0-4 on lines 4-8, a blank line 9, sample 5 on line 10
    path.write_text("\n".join(lines) + "\n")
    text = path.read_text().splitlines()
    assert "nan" in text[7 - 1] and "nan" in text[15 - 1]  # samples 3 and 10
    msg = _error(path)
    assert msg == (f"{path}: columns 'q' (line 7), 'w' (line 15) have NaN; fill or cut these "
                   "samples")


def test_direct_checks_count_rows_from_0():
    with pytest.raises(FlightDataError, match="has NaN at row 3;"):
        check_finite("x.csv", "q", [0.0, 1.0, 2.0, np.nan])


def test_empty_cell_is_nan(tmp_path):
    path = write_csv(tmp_path / "lon_0.csv", lon_flight())
    _edit_cell(path, 40, "w", "")
    msg = _error(path)
    assert "column 'w' has NaN at line 42 (t=0.2 s)" in msg


def test_inf_and_many_rows(tmp_path):
    c = lon_flight()
    c["theta"][100:130] = np.inf
    msg = _error(write_csv(tmp_path / "lon_1.csv", c))
    assert "column 'theta' has infinite values at lines 102, 103, 104, 105, 106 and 25 more" in msg
    assert "(t=0.5 s)" in msg


def test_nan_in_time(tmp_path):
    c = lon_flight()
    c["t"][5] = np.nan
    assert "column 't' has NaN at line 7;" in _error(write_csv(tmp_path / "lon_0.csv", c))


def test_nan_in_extra_column_is_kept(tmp_path):
    c = lon_flight()
    c["note"] = np.where(c["t"] > 2, np.nan, 1.0)
    flight = load_flight(write_csv(tmp_path / "lon_0.csv", c))
    assert np.isnan(np.asarray(flight["note"])).sum() == np.sum(c["t"] > 2)


# ------------------------------------------------------------------ time grid


def test_time_not_increasing(tmp_path):
    c = lon_flight()
    c["t"][57] = c["t"][55]
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "t is not strictly increasing at line 59" in msg
    assert "sort the rows" in msg


def test_time_repeated(tmp_path):
    c = lon_flight()
    c["t"][57] = c["t"][56]
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "t is not strictly increasing at line 59: t repeats 0.28 s" in msg


def test_time_gap(tmp_path):
    c = {k: np.delete(v, 57) for k, v in lon_flight().items()}
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "t is not uniformly sampled" in msg
    assert "step from line 58 to 59 (t=0.28 s) is 0.01 s" in msg
    assert "typical step is 0.005 s" in msg
    assert "resample" in msg


def test_time_jitter_beyond_the_limit(tmp_path):
    c = lon_flight()
    c["t"][100:] += 0.3 * 0.005  # one step 30% long: beyond the jitter fwid resamples
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "not uniformly sampled" in msg and "25%" in msg and "line 101 to 102" in msg


def test_rounded_time_stamps_are_accepted(tmp_path):
    c = lon_flight(rate=300.0)
    c["t"] = np.round(c["t"], 5)  # steps of 0.00333 / 0.00334 s: 0.3% apart
    flight = load_flight(write_csv(tmp_path / "lon_0.csv", c))
    assert np.allclose(np.diff(np.asarray(flight.t)), (c["t"][-1] - c["t"][0]) / (c["t"].size - 1))
    assert time_quantum(c["t"]) == pytest.approx(1e-5)


def test_check_time_direct():
    t = np.arange(100) * 0.01
    assert check_time("x.csv", t) == pytest.approx(0.01)
    t[50:] += 0.0037  # one step 37% off
    with pytest.raises(FlightDataError, match=r"x\.csv: t is not uniformly sampled.*row 49 to 50"):
        check_time("x.csv", t)


# ------------------------------------------------------------------ units


@pytest.mark.parametrize(
    "col, scale, value, what",
    [
        ("theta", 1.0, 1.245, "degrees"),  # 71.3 deg
        ("phi", 1.0, 0.2, "degrees"),
        ("psi", 1.0, 3.0, "degrees"),
        ("q", 1.0, 2.0, "deg/s"),
        ("p", 1.0, 1.5, "deg/s"),
        ("de", 1.0, 0.1, "degrees"),
        ("dr", 1.0, -0.2, "degrees"),
    ],
)
def test_degrees_detected(tmp_path, col, scale, value, what):
    c = lon_flight()
    c[col] = np.degrees(np.full_like(c["t"], value) + 0.01 * np.sin(c["t"]))
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    m = float(np.max(np.abs(c[col])))
    assert f"column '{col}' looks like {what} (max |{col}| = {m:.4g}" in msg
    assert "multiply by pi/180" in msg


def test_degrees_message_matches_the_brief():
    t = np.arange(400) * 0.005
    theta = np.full_like(t, 71.3)
    with pytest.raises(FlightDataError) as info:
        check_flight("lon_0.csv", t, {"theta": theta})
    msg = str(info.value)
    assert msg.startswith("lon_0.csv: column 'theta' looks like degrees (max |theta| = 71.3")
    assert msg.endswith("fwid expects radians: multiply by pi/180")


def test_plausible_radians_pass():
    # a DelFly flies at 70-80 deg pitch: 1.4 rad is fine; heading up to 2 pi; 20 rad/s rates
    check_units(
        "x.csv",
        {"theta": [1.4, -1.0], "phi": [3.1], "psi": [6.2], "q": [-20.0], "de": [0.6], "u": [90]},
    )


def test_unwrapped_heading_hint():
    with pytest.raises(FlightDataError, match="subtract a multiple of 2\\*pi"):
        check_units("x.csv", {"psi": [7.0]})


# ------------------------------------------------------------------ length


def test_too_few_samples(tmp_path):
    c = {k: v[:30] for k, v in lon_flight(rate=20.0, duration=10).items()}
    msg = _error(write_csv(tmp_path / "short.csv", c))
    assert "flight too short to fit: 30 samples over 1.45 s" in msg
    assert "need at least 50 samples and 1 s" in msg


def test_too_short_in_time(tmp_path):
    c = {k: v[:150] for k, v in lon_flight().items()}
    msg = _error(write_csv(tmp_path / "short.csv", c))
    assert "150 samples over 0.745 s" in msg


def test_length_limits_are_inclusive():
    check_length("x.csv", np.arange(50) / 49.0)  # 50 samples over exactly 1 s
    with pytest.raises(FlightDataError, match="49 samples"):
        check_length("x.csv", np.arange(49) / 48.0)


# ------------------------------------------------------------------ flapping frequency


def test_nonpositive_frequency(tmp_path):
    c = lon_flight()
    c["f"][100:103] = 0.0
    msg = _error(write_csv(tmp_path / "lon_0.csv", c))
    assert "column 'f' (flapping frequency, Hz) must be positive" in msg
    assert "lines 102, 103, 104 (t=0.5 s)" in msg


def test_nan_frequency(tmp_path):
    c = lon_flight()
    c["f"][7] = np.nan
    assert "column 'f' has NaN at line 9" in _error(write_csv(tmp_path / "lon_0.csv", c))


def test_check_frequency_direct():
    check_frequency("x.csv", [12.0, 12.5])
    with pytest.raises(FlightDataError, match=r"x\.csv: column 'f'.*-1 at row 1"):
        check_frequency("x.csv", [12.0, -1.0])
    with pytest.raises(FlightDataError, match="infinite"):
        check_frequency("x.csv", [12.0, np.inf])


def test_messages_name_the_path_as_given(tmp_path, monkeypatch):
    """The file's path as the user gave it, folder included (two folders may hold equal
    file names)."""
    c = lon_flight()
    c["q"][3] = np.nan
    sub = tmp_path / "deep" / "folder"
    sub.mkdir(parents=True)
    write_csv(sub / "lon_9.csv", c)
    monkeypatch.chdir(tmp_path)
    msg = _error(Path("deep") / "folder" / "lon_9.csv")
    assert msg.startswith("deep/folder/lon_9.csv: column 'q'"), msg


def test_every_degree_column_named_at_once():
    t = np.arange(400) * 0.005
    cols = {"theta": np.full_like(t, 71.3), "q": np.full_like(t, 120.0), "u": np.ones_like(t)}
    with pytest.raises(FlightDataError) as info:
        check_flight("lon_0.csv", t, cols)
    msg = str(info.value)
    assert msg.startswith("lon_0.csv: columns ") and "'theta' (max 71.3" in msg
    assert "'q' (max 120" in msg and msg.endswith("multiply by pi/180 in each")


def test_radians_that_diverge_are_told_apart_from_degrees():
    # a simulation that diverged: plausible radians first, then past pi; the message still
    # offers the degrees fix, and says when the flight leaves the plausible range
    t = np.arange(400) * 0.005
    theta = 0.3 * np.exp(np.maximum(t - 1.0, 0.0) * 4.0)
    with pytest.raises(FlightDataError) as info:
        check_flight("lon_0.csv", t, {"theta": theta})
    msg = str(info.value)
    first = float(t[np.argmax(np.abs(theta) > np.pi)])
    assert msg.startswith("lon_0.csv: column 'theta' looks like degrees")
    assert f"the flight leaves the plausible range at t = {first:.4g} s" in msg
    assert "diverged" in msg
