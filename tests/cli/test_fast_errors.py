"""Bad input to `fwid identify` and `fwid diagnose` is answered before JAX is imported:
every file is read and checked with numpy first, the one-line message and exit code 2 as
before."""

import json
import subprocess
import sys

import numpy as np
import pytest

from fwid.cli._inputs import DIAGNOSE_COLUMNS, IDENTIFY_COLUMNS
from fwid.synth import write_flights

PROBE = ("import sys, time\nt0 = time.perf_counter()\nfrom fwid.cli import main\n"
         "try:\n    rc = main(sys.argv[1:])\nexcept SystemExit as e:\n    rc = e.code\n"
         "print('jax' in sys.modules, time.perf_counter() - t0)\nsys.exit(rc)")


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    out = tmp_path_factory.mktemp("good")
    write_flights(out, n_flights=1, seed=5, duration=2.0)
    return out / "lon_0.csv"


def _copy(tmp_path, good, edit, folder="bad", vehicle=True):
    lines = good.read_text().splitlines()
    header, rows = lines[0].split(","), [ln.split(",") for ln in lines[1:]]
    header, rows = edit(header, rows)
    d = tmp_path / folder
    d.mkdir()
    if vehicle:
        (d / "vehicle.json").write_text((good.parent / "vehicle.json").read_text())
    path = d / "lon_0.csv"
    path.write_text("\n".join(",".join(r) for r in [header, *rows]) + "\n")
    return path


def _drop(col):
    def edit(header, rows):
        j = header.index(col)
        return header[:j] + header[j + 1:], [r[:j] + r[j + 1:] for r in rows]
    return edit


def _nan(col, row):
    def edit(header, rows):
        rows[row][header.index(col)] = "nan"
        return header, rows
    return edit


def _run(*args, cwd):
    proc = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True,
                          text=True, timeout=120, cwd=cwd)
    jax, seconds = proc.stdout.split()
    return proc, jax == "True", float(seconds)


@pytest.mark.parametrize("case", ["column", "nan", "vehicle", "validate", "diagnose"])
def test_bad_input_exits_2_without_jax(tmp_path, good, case):
    keep = lambda h, r: (h, r)  # noqa: E731
    if case == "column":
        args = ["identify", str(_copy(tmp_path, good, _drop("w"))), "--model", "lon"]
        words = ["lon_0.csv", "missing column 'w'"]
    elif case == "nan":
        args = ["identify", str(_copy(tmp_path, good, _nan("theta", 9))), "--model", "lon"]
        words = ["lon_0.csv", "'theta'", "NaN", "line 11"]
    elif case == "vehicle":
        args = ["identify", str(_copy(tmp_path, good, keep, vehicle=False)), "--model", "lon"]
        words = ["lon_0.csv", "vehicle.json"]
    elif case == "validate":  # a bad held-out flight is found before the training ones load
        args = ["identify", str(good), "--model", "lon", "--validate",
                str(_copy(tmp_path, good, _drop("de")))]
        words = ["bad/lon_0.csv", "'de'"]
    else:
        args = ["diagnose", "--train", str(good), "--test", str(_copy(tmp_path, good,
                                                                      _drop("Z")))]
        words = ["bad/lon_0.csv", "'Z'"]
    proc, jax, seconds = _run(*args, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in proc.stderr, proc.stderr
    for w in words:
        assert w in err[0], err[0]
    assert not jax, "JAX was imported before the bad input was answered"
    assert seconds < 5.0  # in-process time to the answer (well under 1 s on an idle machine)


def _scale_time(factor):
    def edit(header, rows):
        j = header.index("t")
        for r in rows:
            r[j] = repr(float(r[j]) * factor)
        return header, rows
    return edit


@pytest.mark.parametrize("factor, unit", [(1e3, "milliseconds"), (1e6, "microseconds")])
def test_time_not_in_seconds_exits_2_within_3_s(tmp_path, good, factor, unit):
    path = _copy(tmp_path, good, _scale_time(factor))
    proc, jax, seconds = _run("identify", str(path), "--model", "lon", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0], proc.stderr
    assert f"t looks like {unit}" in err[0] and "divide t by" in err[0]
    assert not jax and seconds < 3.0


def test_vehicle_in_grams_exits_2(tmp_path, good):
    path = _copy(tmp_path, good, lambda h, r: (h, r))
    vehicle = json.loads((path.parent / "vehicle.json").read_text())
    (path.parent / "vehicle.json").write_text(json.dumps({**vehicle,
                                                          "mass": vehicle["mass"] * 1e3}))
    proc, jax, seconds = _run("identify", str(path), "--model", "lon", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and str(path.parent / "vehicle.json") in err[0], proc.stderr
    assert "'mass'" in err[0] and "looks like grams" in err[0] and not jax


def test_vehicle_missing_keys_at_once(tmp_path, good):
    path = _copy(tmp_path, good, lambda h, r: (h, r))
    (path.parent / "vehicle.json").write_text('{"mass": 0.02, "Iy": 1e-5}')
    proc, jax, _ = _run("identify", str(path), "--model", "lon", cwd=tmp_path)
    assert proc.returncode == 2 and "missing keys 'Ix', 'Iz'" in proc.stderr, proc.stderr


def test_column_lists_match_the_models():
    """The columns the command line checks before JAX are the models' own."""
    import fwid
    from fwid.diagnosis._signals import REQUIRED

    for name, model in (("lon", fwid.longitudinal()), ("lat", fwid.lateral())):
        assert set(IDENTIFY_COLUMNS[name]) == set(model.states) | set(model.inputs)
    assert DIAGNOSE_COLUMNS == REQUIRED


def test_good_flights_load_as_before(good):
    """Reading with numpy first, building after, gives the flights load_flights gives."""
    import fwid
    from fwid.data import build_flights, read_flights

    a = fwid.load_flights(good.parent)[0]
    b = build_flights(read_flights(good.parent))[0]
    assert a.name == b.name == "lon_0.csv" and a.first_input == b.first_input
    np.testing.assert_array_equal(np.asarray(a.t), np.asarray(b.t))
    for k in a.columns:
        np.testing.assert_array_equal(np.asarray(a.columns[k]), np.asarray(b.columns[k]))
    assert {k: float(v) for k, v in a.trim.items()} == {k: float(v) for k, v in b.trim.items()}
    assert float(a.vehicle.mass) == float(b.vehicle.mass)
