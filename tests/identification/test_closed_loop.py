"""The closed-loop test: a control that answers the states is told from a designed input."""

import numpy as np
import pytest

import fwid
from fwid._advice import command_line
from fwid.identification._closed_loop import closed_loop_test, closed_loop_warning

STATES = ("q", "u", "w", "theta")


def _flight(closed: bool, seed: int = 0, seconds: float = 30.0) -> fwid.Flight:
    """A stable linear vehicle at 100 Hz shaken by process noise; its elevator is a 3211
    repeated (open loop) or an attitude controller's answer to theta and q, holding a pitch
    attitude that the pilot changes now and then (closed loop)."""
    rng = np.random.default_rng(seed)
    dt, n = 0.01, int(seconds / 0.01)
    A = np.array([[-3.0, 0.1, -0.5, 0.0], [0.0, -0.3, 0.2, -9.8],
                  [5.0, -0.2, -2.0, 0.0], [1.0, 0.0, 0.0, 0.0]])
    B = np.array([-20.0, 0.0, -1.0, 0.0])
    pulses = np.repeat([1, 1, 1, -1, -1, 1, -1, 0, 0, 0], 50) * 0.05
    ref = np.repeat(rng.uniform(-0.1, 0.1, n // 150 + 1), 150)
    x, rows, seen = np.zeros(4), [], [np.zeros(4)] * 5
    for k in range(n):
        y = seen[-5] + 0.02 * rng.standard_normal(4)  # what the autopilot saw 50 ms ago
        de = (0.3 * (y[3] - ref[k]) + 0.05 * y[0] + 0.01 * y[1] + 0.02 * y[2] if closed
              else pulses[k % len(pulses)])
        rows.append([*x, de])
        x = x + dt * (A @ x + B * de) + np.sqrt(dt) * 0.3 * rng.standard_normal(4)
        seen.append(x)
    data = np.array(rows)
    columns = {k: data[:, j] for j, k in enumerate((*STATES, "de"))}
    return fwid.Flight(t=np.arange(n) * dt, columns=columns, trim={}, vehicle=None,
                       name=f"{'closed' if closed else 'open'}_{seed}.csv")


@pytest.mark.parametrize("seed", [0, 1])
def test_an_autopilot_is_found_and_a_designed_input_is_not(seed):
    closed = closed_loop_test(_flight(True, seed), "de", STATES)
    opened = closed_loop_test(_flight(False, seed), "de", STATES)
    assert closed.closed and closed.explained > 0.4 and closed.p_value < 1e-6, closed
    assert not opened.closed and opened.explained < 0.25, opened


def test_the_warning_names_the_flight_and_the_method_in_the_users_terms():
    test = closed_loop_test(_flight(True), "de", STATES)
    assert closed_loop_warning([test, None], "lon").startswith("closed_0.csv (de: ")
    assert "method='filter-error'" in closed_loop_warning([test], "lon")
    with command_line():
        note = closed_loop_warning([test], "lon")
    assert "output error is biased" in note and "--method filter-error" in note
    assert closed_loop_warning([closed_loop_test(_flight(False), "de", STATES)], "lon") is None


def test_a_flight_without_the_columns_or_too_short_is_not_judged():
    assert closed_loop_test(_flight(True), "dr", STATES) is None
    assert closed_loop_test(_flight(True, seconds=0.3), "de", STATES) is None


def test_a_derived_input_is_not_tested():
    """An input a model derives from the recorded control (the diagnosis's lagged `de_eff`)
    is not the autopilot's: no closed-loop verdict on it."""
    flight = _flight(closed=True)
    states = ["q", "u", "w", "theta"]
    assert closed_loop_test(flight, "de", states).closed
    derived = flight.with_columns(de_eff=np.asarray(flight["de"]))
    assert closed_loop_test(derived, "de_eff", states) is None
