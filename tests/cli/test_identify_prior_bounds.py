"""`fwid identify --prior PRIOR.json --bounds BOUNDS.json`: both reach the fit and the report."""

import json

import pytest

from fwid.cli import main

PRIOR = {"Mde": {"mean": -0.007, "std": 1e-9}}  # pins Mde (its estimate: -0.0069 +- 3e-5)
# Mq's estimate is -0.001016 +- 6e-6: pushed down to the bound
BOUNDS = {"Mq": {"high": -0.00104}, "Mw": {"low": -1.0, "high": 1.0}}


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    out = tmp_path_factory.mktemp("flights")
    assert main(["simulate", str(out), "--flights", "1", "--seed", "3"]) == 0
    return out / "lon_0.csv"


def _write(path, obj):
    path.write_text(json.dumps(obj))
    return str(path)


@pytest.fixture(scope="module")
def identified(flight, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("prior")
    out = tmp / "report"
    rc = main(["identify", str(flight), "--model", "lon", "--out", str(out), "--figures",
               "none", "--quiet", "--prior", _write(tmp / "prior.json", PRIOR),
               "--bounds", _write(tmp / "bounds.json", BOUNDS)])
    return rc, out, tmp


def test_prior_and_bounds_reach_the_report(identified, capsys):
    rc, out, _ = identified
    assert rc == 0
    report = json.loads((out / "report.json").read_text())
    assert report["fit"]["converged"] and report["fit"]["noise"] == "full"
    assert report["prior"] == {"Mde": {"mean": -0.007, "std": 1e-9}}
    assert report["bounds"]["Mq"] == {"low": None, "high": -0.00104, "active": True,
                                      "at": "high"}
    assert report["bounds"]["Mw"] == {"low": -1.0, "high": 1.0, "active": False, "at": None}
    p = report["parameters"]
    assert p["Mq"]["value"] == -0.00104 and p["Mq"]["std"] is None  # at an active bound
    assert p["Mde"]["value"] == pytest.approx(-0.007, abs=1e-8)
    assert p["Mde"]["std"] == pytest.approx(1e-9, rel=1e-2)  # the prior's: the data add little
    assert all(p[k]["std"] > 0 for k in p if k != "Mq")
    rows = {r.split(",")[0]: r.split(",") for r in
            (out / "parameters.csv").read_text().splitlines()}
    assert rows["Mq"][2] == ""  # no std
    # the contract keys are all still there
    assert set(report) >= {"model", "flights", "parameters", "eigenvalues", "metrics"}


def test_report_as_prior_gives_the_same_fit(identified, flight, capsys):
    """`--prior` also reads a report.json (its parameters' value and std)."""
    _, out, tmp = identified
    first = json.loads((out / "report.json").read_text())
    as_report = {"parameters": {"Mde": {"value": -0.007, "std": 1e-9}}}
    rc = main(["identify", str(flight), "--model", "lon", "--out", str(tmp / "again"),
               "--figures", "none", "--prior", _write(tmp / "report_prior.json", as_report),
               "--bounds", str(tmp / "bounds.json")])
    assert rc == 0
    text = capsys.readouterr().out
    assert "prior (mean +- std): Mde -0.007 +- 1e-09" in text
    assert "bounds: Mq in [open, -0.00104] (active at high), Mw in [-1, 1]" in text
    again = json.loads((tmp / "again" / "report.json").read_text())
    assert again["parameters"] == first["parameters"]


@pytest.mark.parametrize("flag, content, words", [
    ("--bounds", {"Mq": {"low": 0.0, "high": -1.0}}, ["bounds", "'Mq'", "low < high"]),
    ("--bounds", {"Mx": {"low": 0.0}}, ["'Mx'", "not a free parameter", "Mq", "Zde"]),
    ("--prior", {"Mq": {"mean": 0.0, "std": -1.0}}, ["prior", "'Mq'", "positive"]),
    ("--prior", {"Mq": {"mean": 0.0, "sigma": 1.0}}, ["'Mq'", "'sigma'"]),
    ("--prior", [1, 2], ["--prior", "not an object"]),
    ("--prior", None, ["--prior", "no such file"]),
])
def test_bad_prior_or_bounds_exit_2_one_line(flight, tmp_path, capsys, flag, content, words):
    path = tmp_path / "x.json"
    if content is not None:
        path.write_text(json.dumps(content))
    rc = main(["identify", str(flight), "--model", "lon", "--quiet", flag, str(path)])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    for w in words:
        assert w in err, err


def test_prior_on_flapping_model_is_refused(flight, tmp_path, capsys):
    rc = main(["identify", str(flight), "--model", "flap", "--quiet", "--prior",
               _write(tmp_path / "p.json", PRIOR)])
    assert rc == 2
    assert "--model lon or lat" in capsys.readouterr().err
