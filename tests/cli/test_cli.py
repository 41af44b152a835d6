"""The command line per docs/reference/formats.md: exit codes, messages, report.json."""

import json
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

from fwid.cli import main


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    out = tmp_path_factory.mktemp("flights")
    assert main(["simulate", str(out), "--flights", "2", "--seed", "3"]) == 0
    return out


@pytest.fixture(scope="module")
def identified(flights, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    rc = main(["identify", str(flights / "lon_0.csv"), "--model", "lon", "--validate",
               str(flights / "lon_1.csv"), "--out", str(out), "--quiet", "--figures", "all"])
    return rc, out


def test_simulate_writes_contract_columns(flights):
    header = (flights / "lon_0.csv").read_text().splitlines()[0].split(",")
    for col in ("t", "q", "u", "w", "theta", "p", "r", "v", "phi", "de", "dr", "f",
                "X", "Y", "Z", "L", "M", "N"):
        assert col in header
    vehicle = json.loads((flights / "vehicle.json").read_text())
    assert set(vehicle) >= {"mass", "Ix", "Iy", "Iz", "Ixz", "g"}


def test_identify_report_contract(identified):
    rc, out = identified
    assert rc == 0
    report = json.loads((out / "report.json").read_text())
    assert report["model"] == "lon"
    assert report["flights"] == ["lon_0.csv"]
    for k in ("Xq", "Xu", "Xw", "Xde", "Zq", "Zu", "Zw", "Zde", "Mq", "Mu", "Mw", "Mde"):
        assert set(report["parameters"][k]) >= {"value", "std"}
        assert report["parameters"][k]["std"] > 0
    eig = np.array(report["eigenvalues"])
    assert eig.shape == (4, 2) and np.all(eig[:, 0] < 0)
    for part in ("estimation", "validation"):
        for out_name in ("q", "u", "w", "theta"):
            m = report["metrics"][part][out_name]
            assert set(m) >= {"corr", "r2", "rms", "rms_pct"}
            assert m["corr"] > 0.9
    for fig in ("fit_lon_0.png", "validation_lon_1.png", "poles.png", "fits.png"):
        assert (out / fig).stat().st_size > 10_000


def test_identified_short_period_matches_table3(identified):
    _, out = identified
    eig = np.array(json.loads((out / "report.json").read_text())["eigenvalues"])
    osc = eig[np.argmax(np.abs(eig[:, 1]))]
    # Table 3: -1.3538 +/- 5.6483i; the noisy simulated flight gives it within 3 %
    assert abs(complex(*osc) - complex(-1.3538, 5.6483)) / abs(complex(-1.3538, 5.6483)) < 0.03


def _bad(tmp_path, flights, name, edit):
    """Copy lon_0.csv with one edit applied to its rows (a list of lists of str)."""
    lines = (flights / "lon_0.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = [ln.split(",") for ln in lines[1:]]
    header, rows = edit(header, rows)
    folder = tmp_path / "bad"
    folder.mkdir(exist_ok=True)
    (folder / "vehicle.json").write_text((flights / "vehicle.json").read_text())
    (folder / name).write_text("\n".join(",".join(r) for r in [header, *rows]) + "\n")
    return folder / name


def _drop_column(col):
    def edit(header, rows):
        j = header.index(col)
        return header[:j] + header[j + 1:], [r[:j] + r[j + 1:] for r in rows]
    return edit


def _set(col, row, value):
    def edit(header, rows):
        rows[row][header.index(col)] = value
        return header, rows
    return edit


def _scale(col, factor):
    def edit(header, rows):
        j = header.index(col)
        for r in rows:
            r[j] = repr(float(r[j]) * factor)
        return header, rows
    return edit


@pytest.mark.parametrize("name, edit, words", [
    ("nocol.csv", _drop_column("w"), ["nocol.csv", "'w'"]),
    ("nan.csv", _set("q", 17, "nan"), ["nan.csv", "'q'", "NaN", "line 19"]),
    ("deg.csv", _scale("theta", 180 / np.pi), ["deg.csv", "theta", "degrees"]),
    ("nonuni.csv", _set("t", 300, "1.5013"), ["nonuni.csv", "uniform"]),
    ("short.csv", lambda h, r: (h, r[:30]), ["short.csv", "short"]),
])
def test_bad_input_exit_2_one_line(tmp_path, flights, capsys, name, edit, words):
    path = _bad(tmp_path, flights, name, edit)
    out = tmp_path / "out"
    out.mkdir()
    (out / "report.json").write_text('{"previous": true}')
    rc = main(["identify", str(path), "--model", "lon", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1, err
    for w in words:
        assert w.lower() in err.lower(), err
    # nothing already written is lost
    assert json.loads((out / "report.json").read_text()) == {"previous": True}


def test_no_excitation_is_bad_input(tmp_path, flights, capsys):
    def flat(header, rows):
        j = header.index("de")
        for r in rows:
            r[j] = "0.04"
        return header, rows

    path = _bad(tmp_path, flights, "flat.csv", flat)
    rc = main(["identify", str(path), "--model", "lon", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and "flat.csv" in err and "never moves" in err


def test_entry_point_exit_code_and_message(tmp_path):
    missing = tmp_path / "nope.csv"
    proc = subprocess.run([sys.executable, "-m", "fwid.cli", "identify", str(missing),
                           "--model", "lon"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "nope.csv" in proc.stderr and "Traceback" not in proc.stderr


def test_diagnose_writes_contract_report_and_summary(tmp_path, capsys):
    train, test, out = tmp_path / "train", tmp_path / "test", tmp_path / "out"
    for folder, seed in ((train, 11), (test, 12)):
        assert main(["simulate", str(folder), "--flights", "8", "--seed", str(seed),
                     "--effect", "nonlinear-aero", "--strength", "1.5"]) == 0
    capsys.readouterr()
    # the training flights come from fwid reconstruct (docs/reference/formats.md), the test ones not
    (train / "reconstruction.json").write_text(json.dumps({"flights": [
        {"flight": p.name, "source": "motive", "clock_offset_s": -2.0, "dropouts": [],
         "warnings": []} for p in sorted(train.glob("*.csv"))]}))
    assert main(["diagnose", "--train", str(train), "--test", str(test), "--out", str(out),
                 "--quiet", "--no-simulation", "--no-process-noise"]) == 0
    text = capsys.readouterr().out
    assert "VERDICT: nonlinear-aero" in text
    assert "states: 8 of 16 flights rebuilt from raw recordings by fwid reconstruct" in text
    rep = json.loads((out / "diagnosis.json").read_text())
    assert rep["verdict"] == "nonlinear-aero"
    assert rep["states"]["reconstructed"] == "some" and len(rep["states"]["missing"]) == 8
    assert rep["confidence_set"][0]["explanation"][0] == "nonlinear-aero"
    top = rep["candidates"][0]
    assert top["effect"] == "nonlinear-aero" and top["significant"] and top["shrink_pct"] > 0
    assert set(top["test_rms_before"]) == {"X", "Y", "Z", "L", "M", "N"}
    assert rep["localisation"]["by_output"]
    assert (out / "gap_map.png").stat().st_size > 10_000
    assert rep["simulation"] is None and not (out / "gap_sim.png").exists()
    assert rep["process_noise"] is None  # (only with a random-disturbance verdict)
    # where the flights are (for `fwid design --discriminate`), beside their names
    assert [Path(p).name for p in rep["method"]["train_paths"]] == rep["train"]
    assert all(Path(p).is_file() for p in rep["method"]["train_paths"] + rep["method"]["test_paths"])
    # bad input: exit 2, one line, the earlier report untouched
    before = (out / "diagnosis.json").read_text()
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "vehicle.json").write_text((train / "vehicle.json").read_text())
    lines = (train / "lon_0.csv").read_text().splitlines()
    cols = lines[0].split(",")
    keep = [i for i, c in enumerate(cols) if c != "Z"]
    (tmp_path / "bad" / "lon_0.csv").write_text(
        "\n".join(",".join(row.split(",")[i] for i in keep) for row in lines) + "\n")
    assert main(["diagnose", "--train", str(tmp_path / "bad"), "--test", str(test), "--out",
                 str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "lon_0.csv" in err[0] and "'Z'" in err[0]
    assert (out / "diagnosis.json").read_text() == before


def test_report_is_readable_by_others(identified):
    """report.json gets the mode of any file the user writes (0644 under umask 022), not the
    atomic write's temporary 0600."""
    import os

    rc, out = identified
    umask = os.umask(0)
    os.umask(umask)
    assert (out / "report.json").stat().st_mode & 0o777 == 0o666 & ~umask


def test_bad_effect_exits_2_and_writes_nothing(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["simulate", str(tmp_path / "x"), "--effect", "actuator-lag"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "actuator-lag" in err and "actuator-dynamics" in err  # the choices are listed
    assert not (tmp_path / "x").exists()


def test_help_lists_effects_and_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["simulate", "--help"])
    assert info.value.code == 0
    import re

    text = re.sub(r"-\s+", "-", capsys.readouterr().out)  # argparse wraps at hyphens
    for effect in ("flap-coupling", "nonlinear-aero", "lon-lat-coupling", "actuator-dynamics"):
        assert effect in text
    assert "(default: 4)" in text  # defaults shown
    with pytest.raises(SystemExit):
        main(["--version"])
    import fwid

    assert capsys.readouterr().out.strip() == f"fwid {fwid.__version__}"


def test_equal_file_names_in_two_folders_give_distinct_figures(flights, tmp_path, capsys):
    """Two folders with the same file names: distinct flight names in the report and
    distinct figure files; without --out, a note says nothing was written."""
    import shutil

    for sub in ("clean", "demo"):
        (tmp_path / sub).mkdir()
        for name in ("lon_0.csv", "vehicle.json"):
            shutil.copy(flights / name, tmp_path / sub / name)
    out = tmp_path / "out"
    assert main(["identify", str(tmp_path / "clean"), str(tmp_path / "demo"), "--model", "lon",
                 "--out", str(out), "--quiet", "--figures", "all"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["flights"] == ["clean/lon_0.csv", "demo/lon_0.csv"]
    assert {p.name for p in out.glob("fit_*.png")} == {"fit_clean__lon_0.png",
                                                         "fit_demo__lon_0.png"}
    capsys.readouterr()
    assert main(["identify", str(tmp_path / "clean"), "--model", "lon", "--quiet"]) == 0
    assert "nothing written" in capsys.readouterr().out


def test_model_leaves_fwid(identified):
    """report.json carries A, B, C, D with names; parameters.csv has value, std, std_cr and
    the relative std beside it, equal to the report's."""
    import csv

    rc, out = identified
    report = json.loads((out / "report.json").read_text())
    ss = report["state_space"]
    assert ss["states"] == ["q", "u", "w", "theta"] and ss["inputs"] == ["de"]
    A = np.array(ss["A"])
    ev = sorted(np.linalg.eigvals(A), key=lambda e: (e.real, e.imag))
    want = sorted((complex(*e) for e in report["eigenvalues"]), key=lambda e: (e.real, e.imag))
    np.testing.assert_allclose(ev, want, rtol=1e-8)
    rows = list(csv.DictReader((out / "parameters.csv").open()))
    assert [r["name"] for r in rows] == list(report["parameters"])
    for r in rows:
        p = report["parameters"][r["name"]]
        assert float(r["value"]) == pytest.approx(p["value"], rel=1e-9)
        assert float(r["std"]) == pytest.approx(p["std"], rel=1e-9)
        assert float(r["rel_std_pct"]) == pytest.approx(100 * abs(p["std"] / p["value"]), rel=1e-6)


def test_template_folder_identifies(tmp_path, capsys):
    """`fwid template DIR` writes an example folder that `fwid identify` reads as is; a
    non-empty folder is refused (exit 2) and left alone."""
    out = tmp_path / "mine"
    assert main(["template", str(out)]) == 0
    assert {"lon_0.csv", "vehicle.json", "README.txt"} <= {p.name for p in out.iterdir()}
    guide = (out / "README.txt").read_text()
    assert "RADIANS" in guide and "vehicle.json" in guide
    assert main(["identify", str(out), "--model", "lon", "--quiet"]) == 0
    before = sorted(p.name for p in out.iterdir())
    assert main(["template", str(out)]) == 2
    assert "not empty" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == before


def test_identify_report_has_an_empty_warnings_list_when_all_is_well(identified):
    _, out = identified
    report = json.loads((out / "report.json").read_text())
    assert report["warnings"] == []
    # the low-passed demo flights' residuals are white at the data's bandwidth: full R kept
    assert report["fit"]["noise"] == "full"
    colour = report["fit"]["residual_colour"]
    assert set(colour) == {"q", "u", "w", "theta"} and max(colour.values()) < 0.5


def test_identify_exits_1_when_no_flight_converged(flights, tmp_path, monkeypatch, capsys):
    import functools
    import importlib

    pipeline = importlib.import_module("fwid.identification._cycle_averaged")
    monkeypatch.setattr(pipeline, "fit", functools.partial(pipeline.fit, max_steps=1))
    rc = main(["identify", str(flights / "lon_0.csv"), "--model", "lon",
               "--out", str(tmp_path), "--quiet"])
    assert rc == 1
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "no fit converged (flights: lon_0.csv): " in err[0], err
    assert "stalled" in err[0]
    note = "WARNING: lon_0.csv: the lon fit did not converge in 1 Gauss-Newton step"
    assert captured.out.count(note) == 1  # once, one line, no source location
    assert "UserWarning" not in captured.out + captured.err
    # advice in the command line's terms: the one next step, an option of fwid identify
    assert "next: --method multiple-shooting" in captured.out and "fwid.fit" not in captured.out
    report = json.loads((tmp_path / "report.json").read_text())  # still written
    assert report["fit"]["converged"] is False
    assert any("did not converge" in w for w in report["warnings"])


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["identify", "--help"],
                                  ["identify", "nope.csv", "--model", "lon"],
                                  ["diagnose", "--train", "nope", "--test", "nope"]])
def test_start_up_without_jax_or_matplotlib(args, tmp_path):
    """Help, version and a missing file are answered before JAX or matplotlib is imported."""
    probe = ("import sys\nfrom fwid.cli import main\ntry:\n    rc = main(sys.argv[1:])\n"
             "except SystemExit as e:\n    rc = e.code\n"
             "heavy = [m for m in ('jax', 'matplotlib', 'diffrax', 'numpy') if m in sys.modules]\n"
             "print('heavy:', heavy)\nsys.exit(rc)")
    proc = subprocess.run([sys.executable, "-c", probe, *args], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert proc.returncode == (2 if "nope" in str(args) else 0), proc.stderr
    assert "heavy: []" in proc.stdout
    if "nope" in str(args):
        assert proc.stderr.strip().splitlines() == [
            "fwid: error: nope" + (".csv" if "identify" in args else "")
            + ": no such file or folder"]


def test_figures_summary_by_default_or_none(flights, tmp_path):
    """By default one overview of the fits and the poles, no figure per flight; `none`: no
    figure at all (the report still whole)."""
    for figures, pngs in ((None, {"fits.png", "poles.png"}), ("none", set())):
        out = tmp_path / str(figures)
        extra = ["--figures", figures] if figures else []
        assert main(["identify", str(flights), "--model", "lon", "--out", str(out), "--quiet",
                     *extra]) == 0
        assert {p.name for p in out.glob("*.png")} == pngs
        assert (out / "report.json").exists()
