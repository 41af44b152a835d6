"""`fwid design` (docs/reference/formats.md): the files and their columns, the one-line errors."""

import csv
import json

import numpy as np
import pytest

from fwid.cli import main
from tests.design.conftest import lon_report


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli_design") / "report.json"
    path.write_text(json.dumps(lon_report()))
    return path


def test_design_writes_the_contract_files(report, tmp_path):
    out = tmp_path / "des"
    rc = main(["design", "--model", "lon", "--from", str(report), "--duration", "2.5",
               "--amplitude", "0.08", "--quiet", "0.5", "--out", str(out), "--restarts", "1",
               "--rate", "40", "--no-progress"])
    assert rc == 0
    with open(out / "input.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:2] == ["t", "de"]
    t = np.array([float(r["t"]) for r in rows])
    de = np.array([float(r["de"]) for r in rows])
    assert t[0] == 0.0 and t[-1] <= 2.5 + 1e-9 and np.all(np.diff(t) > 0)
    assert np.max(np.abs(de)) <= 0.08 + 1e-12 and np.max(np.abs(de)) > 0.04
    assert np.all(de[t <= 0.5] == 0.0)
    d = json.loads((out / "design.json").read_text())
    assert set(d["parameters"]) >= {"Xq", "Zw", "Mq", "Mde"}
    for row in d["parameters"].values():
        assert row["ratio"] == pytest.approx(row["3211"] / row["designed"])
    assert d["limits"]["amplitude_rad"] == 0.08 and d["limits"]["quiet_s"] == 0.5
    assert (out / "design.png").stat().st_size > 1000


@pytest.mark.parametrize("args, message", [
    (["--amplitude", "0"], "amplitude must be > 0"),
    (["--amplitude", "0.1", "--quiet", "3", "--duration", "3"], "quiet start"),
    (["--amplitude", "0.1", "--model", "lat"], "not 'lat'"),
])
def test_bad_arguments_exit_2_with_one_line(report, tmp_path, capsys, args, message):
    argv = ["design", "--from", str(report), "--out", str(tmp_path / "x")]
    if "--model" not in args:
        argv += ["--model", "lon"]
    assert main(argv + args) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "x" / "input.csv").exists()


def test_a_missing_report_is_named(tmp_path, capsys):
    assert main(["design", "--model", "lon", "--from", str(tmp_path / "no.json"),
                 "--amplitude", "0.1", "--out", str(tmp_path / "x")]) == 2
    assert "no.json" in capsys.readouterr().err


def test_discriminate_without_the_flights_says_what_is_missing(tmp_path, capsys):
    (tmp_path / "diagnosis.json").write_text(json.dumps({
        "verdict": "actuator-dynamics", "axis": "lon", "train": ["lon_0.csv"],
        "effects": [{"effect": "actuator-dynamics", "near_tie": True,
                     "runner_up": {"effect": "time-offset", "gain_ratio": 0.97}}],
        "candidates": [{"effect": "actuator-dynamics", "variant": "first-order lag, tau = 0.04 s"},
                       {"effect": "time-offset", "variant": "0.03 s"}],
        "method": {}}))
    assert main(["design", "--discriminate", str(tmp_path), "--amplitude", "0.1",
                 "--out", str(tmp_path / "x")]) == 2
    assert "--train" in capsys.readouterr().err


def test_the_close_pair_and_its_variants_are_read_back():
    from fwid.cli._discriminate import close_pair

    diag = {"effects": [{"effect": "actuator-dynamics", "near_tie": False, "runner_up": None},
                        {"effect": "nonlinear-aero", "near_tie": True,
                         "runner_up": {"effect": "unsteady-aero", "gain_ratio": 0.9}}],
            "candidates": [{"effect": "nonlinear-aero", "variant": None},
                           {"effect": "unsteady-aero", "variant": "0.05 s"},
                           {"effect": "actuator-dynamics", "variant": "delay 0.02 s"}]}
    assert close_pair(diag) == [("nonlinear-aero", None), ("unsteady-aero", 0.05)]
    # with a confidence set: the first entries of its first two explanations that differ
    diag["confidence_set"] = [{"explanation": ["actuator-dynamics", "attitude"]},
                              {"explanation": ["actuator-dynamics", "nonlinear-aero"]},
                              {"explanation": ["nonlinear-aero"]}]
    diag["candidates"][0]["variant"] = "smooth in w (2 degrees of freedom each)"
    assert close_pair(diag) == [("actuator-dynamics", ("delay", 0.02)),
                                ("nonlinear-aero", None)]  # its words alone cannot form it
    # with its member, every number of it is read back
    from fwid.diagnosis._catalogue import member_json
    from fwid.diagnosis._catalogue._smooth import smooth_basis
    from fwid.diagnosis._catalogue.nonlinear_aero import Terms

    terms = Terms((1,), 2, bases={"w": smooth_basis(np.linspace(-1.0, 1.0, 400))})
    diag["candidates"][0]["member"] = json.loads(json.dumps(member_json(terms)))
    (_, got), (name, back) = close_pair(diag)
    assert name == "nonlinear-aero" and back == terms
    x = np.linspace(-2.0, 2.0, 50)
    np.testing.assert_array_equal(back.bases["w"](x), terms.bases["w"](x))
