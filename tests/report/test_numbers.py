"""Printed numbers stay in their columns whatever a fit gave; report.json never holds NaN."""

import json
import math

import pytest

from fwid.report import write_json
from fwid.report._numbers import compact, fixed, score
from fwid.report._table import metrics_table, modes_table, parameter_table

HOSTILE = [-2.5e7, -1.7e255, 6e126, float("nan"), float("inf"), float("-inf"), 1e-300, None]


@pytest.mark.parametrize("x", HOSTILE + [0.63, -12.5, 1.0])
@pytest.mark.parametrize("width", [8, 9, 11])
def test_fixed_and_score_keep_their_width_and_a_leading_space(x, width):
    for text in (fixed(x, width), score(x, width), score(x, 7)):
        assert text[0] == " " and len(text) in (width, 7), repr(text)


def test_scores_far_below_zero_print_as_a_floor():
    assert score(-25435412.13, 8).strip() == "<-1e3"
    assert score(0.63, 8).strip() == "0.63"
    assert compact(-2.5e7) == "<-1e3" and compact(0.874) == "0.87"
    assert fixed(6e126, 8).strip() == "6e+126"


def test_metrics_table_columns_never_run_together():
    rows = {"q": {"corr": 0.63, "r2": -25435412.13, "rms": 6e126, "rms_pct": 1.4e110},
            "u": {"corr": float("nan"), "r2": -1.7e255, "rms": 0.1, "rms_pct": 12.0}}
    lines = metrics_table(rows).splitlines()
    assert len({len(line) for line in lines}) == 1, lines  # every row as wide as the header
    assert "0.63   <-1e3" in lines[1]
    for line in lines[1:]:
        assert len(line.split()) == 6, line  # output, corr, R2, RMS, unit, % range


def test_modes_and_parameters_of_a_runaway_fit_stay_short():
    modes = [{"kind": "oscillatory", "eigenvalue": [-3.1e200, 2.4], "wn": 1e201, "zeta": 0.7},
             {"kind": "aperiodic", "eigenvalue": [5.2, 0.0], "tau": -0.19}]
    assert max(len(line) for line in modes_table(modes).splitlines()) <= 63
    table = parameter_table({"Mq": {"value": 1e-9, "std": 1e200}, "Xu": {"value": 0.0}})
    assert max(len(line) for line in table.splitlines()) <= 3 * 38 + 4


def test_report_json_holds_null_for_non_finite_numbers(tmp_path):
    path = write_json(tmp_path / "r.json", {"r2": float("nan"), "m": [float("inf"), 1.0]})
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == {"r2": None, "m": [None, 1.0]}
    assert math.isfinite(json.loads(text)["m"][1])

