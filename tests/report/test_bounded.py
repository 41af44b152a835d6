"""Bounded output: a parameter the flights cannot fix prints as "not identifiable from these
flights", a simulation that ran away as "diverged at t = ... s", a figure keeps its axis to
the measured range; report.json keeps the raw numbers beside the verdicts."""

import re

import numpy as np

from fwid.identification._flight_fit import flight_fit
from fwid.report import identification_summary, parameters_csv, plot_flight_fit, \
    plot_fits_overview
from fwid.report._bounded import diverged_at, identifiable, mark_diverged, with_identifiable


def _numbers(text):
    return [abs(float(x)) for x in re.findall(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?", text)]


def _diverging():
    """A flight fit whose simulated q grows as exp(t) past a measured range of 2: beyond
    100 ranges above the measured maximum from t = ln(201) = 5.30 s on."""
    t = np.arange(0, 10, 0.01)
    z = np.column_stack([np.sin(t), 0.1 * np.cos(t)])
    y = np.column_stack([np.exp(t), 0.1 * np.cos(t) + 0.01])
    return flight_fit("f.csv", t, {"de": np.sign(np.sin(3 * t))}, ("q", "u"), z, y)


def test_identifiable_is_a_thousandfold_std_or_not_finite():
    assert identifiable(1e-3, 0.99) is True and identifiable(-1e-3, 1.01) is False
    assert identifiable(0.2, 1e48) is False and identifiable(0.2, float("nan")) is False
    assert identifiable(float("inf"), 1.0) is False and identifiable(0.2, None) is None


def test_diverged_at_is_the_first_time_beyond_a_hundred_ranges_or_not_finite():
    ff = _diverging()
    at = diverged_at(ff.t, ff.measured["q"], ff.simulated["q"])
    assert abs(at - np.log(201.0)) < 0.011
    assert diverged_at(ff.t, ff.measured["u"], ff.simulated["u"]) is None
    y = np.zeros(5)
    y[3] = np.nan
    assert diverged_at(np.arange(5.0), np.arange(5.0), y) == 3.0


def _report(ff):
    params = {"Mq": {"value": -6.8e-4, "std": 1e48, "std_cr": 1e48, "rel_std_pct": 1.5e53},
              "Mde": {"value": 0.12, "std": 0.01, "std_cr": 0.01, "rel_std_pct": 8.3}}
    return {"model": "lon", "flights": ["f.csv"], "parameters": with_identifiable(params),
            "modes": [], "metrics": {"estimation": mark_diverged(ff.metrics, [ff])},
            "warnings": []}


def test_the_summary_says_not_identifiable_and_diverged_instead_of_the_numbers():
    ff = _diverging()
    report = _report(ff)
    assert report["parameters"]["Mq"]["identifiable"] is False
    assert report["parameters"]["Mde"]["identifiable"] is True
    q = report["metrics"]["estimation"]["q"]
    assert q["rms"] > 1e3 and abs(q["diverged_at_s"] - 5.31) < 1e-9 and q["diverged_in"] == "f.csv"
    assert "diverged_at_s" not in report["metrics"]["estimation"]["u"]
    text = identification_summary(report)
    mq = next(line for line in text.splitlines() if line.startswith("Mq"))
    assert "not identifiable" in mq and "e+48" not in text
    assert "not identifiable from these flights: Mq (" in text
    assert "q         simulation diverged at t = 5.31 s (f.csv)" in text
    assert max(_numbers(text)) <= 1e3, text
    u = next(line for line in text.splitlines() if line.startswith("u "))
    assert "diverged" not in u and "0.010" not in u  # u is scored as usual


def test_parameters_csv_says_identifiable_and_leaves_out_the_spreads_of_the_rest():
    rows = parameters_csv(_report(_diverging())["parameters"]).splitlines()
    assert rows[0] == "name,value,std,std_cr,rel_std_pct,identifiable"
    assert rows[1] == "Mq,-0.00068,,,,false"
    assert rows[2] == "Mde,0.12,0.01,0.01,8.333333333,true"


def test_figures_keep_the_axis_to_the_measured_range_and_mark_the_divergence():
    ff = _diverging()
    fig = plot_flight_fit(ff)
    q_ax = fig.axes[0]
    lo, hi = q_ax.get_ylim()
    zq = np.rad2deg(ff.measured["q"])  # rates in degrees
    span = np.ptp(zq)
    assert lo >= zq.min() - span and hi <= zq.max() + span
    assert any("diverged at t = 5.31 s" in t.get_text() for t in q_ax.texts)
    over = plot_fits_overview([ff])
    lo, hi = over.axes[0].get_ylim()
    assert hi <= zq.max() + span
    assert any("diverged at t = 5.31 s" in t.get_text() for t in over.axes[0].texts)
    assert not any("diverged" in t.get_text() for t in over.axes[1].texts)  # u did not
