"""`fwid identify --method`, and the one-line refusals of flights that cannot be identified."""

import csv
import json

import pytest

from fwid.cli import main


def _edited(flight, tmp_path, edit):
    rows = list(csv.reader(flight.read_text().splitlines()))
    head, body = edit(rows[0], rows[1:])
    path = tmp_path / "edited.csv"
    path.write_text("\n".join(",".join(r) for r in [head, *body]) + "\n")
    (tmp_path / "vehicle.json").write_text((flight.parent / "vehicle.json").read_text())
    return path


def test_multiple_shooting_from_the_command_line(flight, tmp_path, capsys):
    out = tmp_path / "ms"
    rc = main(["identify", str(flight), "--model", "lon", "--method", "multiple-shooting",
               "--out", str(out), "--figures", "none", "--quiet"])
    assert rc == 0, capsys.readouterr().err
    report = json.loads((out / "report.json").read_text())
    assert report["method"] == "multiple-shooting" and report["fit"]["converged"]
    assert report["parameters"]["Mq"]["value"] < 0
    assert report["closed_loop"]["lon_0.csv"]["closed"] is False  # a designed 3211


@pytest.mark.parametrize("method", ["multiple-shooting", "filter-error"])
def test_prior_and_bounds_are_refused_in_one_line_with_the_other_methods(flight, tmp_path,
                                                                         capsys, method):
    prior = tmp_path / "prior.json"
    prior.write_text('{"Mq": {"mean": -0.001, "std": 0.0002}}')
    rc = main(["identify", str(flight), "--model", "lon", "--method", method,
               "--prior", str(prior), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert f"--method {method}" in err[0] and "work with --method output-error only" in err[0]
    assert "fit by output error" in err[0]


def test_method_is_refused_for_the_flapping_model(flight, capsys):
    rc = main(["identify", str(flight), "--model", "flap", "--method", "filter-error"])
    assert rc == 2 and "applies to --model lon or lat" in capsys.readouterr().err


@pytest.mark.parametrize("edit", ["drop", "zero"])
def test_flights_without_controls_are_refused_in_one_line(flight, tmp_path, capsys, edit):
    def change(head, body):
        j = head.index("de")
        if edit == "drop":
            return head[:j] + head[j + 1:], [r[:j] + r[j + 1:] for r in body]
        return head, [r[:j] + ["0"] + r[j + 1:] for r in body]

    rc = main(["identify", str(_edited(flight, tmp_path, change)), "--model", "lon"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "the flights carry no controls" in err[0], err
