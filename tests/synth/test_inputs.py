"""Identification inputs (doublet, 3211, 211, pulse) and how flights use them."""

import numpy as np
import pytest

from fwid.synth import (
    DEFAULT_UNIT,
    INPUTS,
    doublet,
    input_211,
    input_3211,
    make_input,
    pulse,
    simulate_flight,
)

PATTERNS = {
    "doublet": (doublet, [1, -1]),
    "3211": (input_3211, [1, 1, 1, -1, -1, 1, -1]),
    "211": (input_211, [1, 1, -1, 1]),
    "pulse": (pulse, [1]),
}


@pytest.mark.parametrize("name", list(PATTERNS))
def test_pattern_quiet_start_and_end(name):
    fn, pattern = PATTERNS[name]
    start, unit, amp = 1.0, 0.15, 0.08
    mids = start + unit * (np.arange(len(pattern)) + 0.5)
    np.testing.assert_allclose(fn(mids, start, unit, amp), amp * np.array(pattern))
    t = np.arange(0, 4, 0.005)
    y = fn(t, start, unit, amp)
    assert np.all(y[t < start - 1e-6] == 0.0)  # quiet trim start
    assert np.all(y[t >= start + len(pattern) * unit + 1e-6] == 0.0)
    assert set(np.unique(y)) <= {0.0, amp, -amp}
    # sampled on a 200 Hz grid, each step lasts unit / dt samples
    n_on = np.count_nonzero(y)
    assert n_on == round(len(pattern) * unit / 0.005)
    np.testing.assert_array_equal(make_input(name, t, start, unit, amp), y)
    assert INPUTS[name] is fn


def test_edges_are_half_open_and_robust_to_rounding():
    t = np.array([0.9999999999, 1.0, 1.2999999999, 1.3, 1.6])
    np.testing.assert_array_equal(doublet(t, 1.0, 0.3, 1.0), [1.0, 1.0, -1.0, -1.0, 0.0])


def test_default_units_and_errors():
    assert set(DEFAULT_UNIT) == set(INPUTS)
    t = np.linspace(0, 3, 601)
    np.testing.assert_array_equal(
        make_input("3211", t, 1.0, None, 0.1), input_3211(t, 1.0, DEFAULT_UNIT["3211"], 0.1)
    )
    with pytest.raises(ValueError):
        make_input("sweep", t, 1.0, None, 0.1)
    with pytest.raises(ValueError):
        doublet(t, 1.0, 0.0, 0.1)


@pytest.mark.parametrize("axis", ["lon", "lat"])
def test_flight_uses_elevator_for_lon_rudder_for_lat(axis):
    fl = simulate_flight(axis=axis, input="211", start=1.2, amplitude=0.1, noise=0.0, ripple=False)
    meta = fl["meta"]
    used, other = ("de", "dr") if axis == "lon" else ("dr", "de")
    cmd = fl[used] - meta["trim"][used + "0"]
    np.testing.assert_allclose(cmd, make_input("211", fl["t"], 1.2, None, 0.1), atol=1e-15)
    assert np.all(fl[other] == meta["trim"][other + "0"])
    k0 = meta["first_input"]
    assert fl["t"][k0] == pytest.approx(1.2)
    # quiet start: the cycle-averaged states stay exactly at trim before the input
    assert np.all(meta["states_cycle_averaged"][:k0] == 0.0)
    assert meta["truth"]["input"] == {
        "type": "211",
        "surface": used,
        "start": 1.2,
        "unit": DEFAULT_UNIT["211"],
        "amplitude": 0.1,
        "n_units": 4,
    }


def test_quiet_start_with_flapping_is_cycle_averaged_trim():
    # starting on the periodic flapping orbit, the quiet start has no start-up transient
    fl = simulate_flight(axis="lon", amplitude=0.0, noise=0.0, ripple=False, drift=False)
    x = fl["meta"]["states"]
    n_cycle = round(200 / 12.5)  # 16 samples: one flap cycle at 12.5 Hz
    for k in (0, 50, 100, 150):
        seg = x[k : k + n_cycle * 5]
        assert np.all(np.abs(seg.mean(axis=0)) < 0.06 * seg.std(axis=0) + 1e-6)
