import jax.numpy as jnp
import numpy as np
import pytest

from fwid.data import estimate_trim, first_input_index
from fwid.data._trim import input_column, smooth_input

from .helpers import LAT_TRIM, LON_TRIM, lat_flight, lon_flight


def _expected(t_input, rate):
    return int(np.ceil(t_input * rate - 1e-9))


@pytest.mark.parametrize("shape", ["doublet", "step", "211"])
@pytest.mark.parametrize("rate", [100.0, 200.0, 500.0])
def test_first_input_shapes_and_rates(shape, rate):
    c = lon_flight(rate=rate, shape=shape, t_input=1.0)
    i = first_input_index(c["t"], c["de"])
    assert i is not None
    # within 1 sample, or 5 ms at high rates
    assert abs(i - _expected(1.0, rate)) <= max(1, int(0.005 * rate))


@pytest.mark.parametrize(
    "ripple, amp, f_flap, t_input",
    [
        (0.02, 0.05, 12.0, 1.0),  # the brief's example: 12 Hz ripple, doublet at 1 s
        (0.10, 0.05, 12.5, 1.73),  # ripple twice the input
        (0.15, 0.03, 13.3, 0.6),  # ripple five times the input, awkward period
        (0.02, 0.05, 11.0, 2.11),
        (0.00, 0.05, 12.0, 1.0),  # no ripple at all
    ],
)
def test_first_input_ignores_flapping_ripple(ripple, amp, f_flap, t_input):
    c = lon_flight(ripple=ripple, amp=amp, f_flap=f_flap, t_input=t_input)
    i = first_input_index(c["t"], c["de"])
    assert i is not None
    assert abs(i - _expected(t_input, 200.0)) <= 2


@pytest.mark.parametrize("t_input", [0.6, 1.37, 2.11])
def test_first_input_with_drifting_flapping_frequency(t_input):
    # flapping at 12.5 -> 13.3 Hz over the flight, with a second harmonic, ripple 2x input
    c = lon_flight(rate=1000.0, ripple=0.0, amp=0.05, t_input=t_input, shape="211")
    t = c["t"]
    phase = 2 * np.pi * (12.5 * t + 0.1 * t**2)
    de = c["de"] + 0.1 * (np.sin(phase) + 0.3 * np.sin(2 * phase + 1.0))
    assert abs(first_input_index(t, de) - _expected(t_input, 1000.0)) <= 3


def test_first_input_is_not_the_ripple_onset():
    # Without the smoothing, the ripple (4x the input) departs from the level at once.
    c = lon_flight(ripple=0.2, amp=0.05, t_input=2.0)
    i = first_input_index(c["t"], c["de"])
    assert abs(i - 400) <= 2


def test_first_input_none_when_the_input_does_not_vary():
    t = np.arange(800) / 200.0
    rng = np.random.default_rng(3)
    assert first_input_index(t, np.full(800, 0.05)) is None
    rippling = 0.05 + 0.02 * np.sin(2 * np.pi * 12.3 * t) + 0.002 * rng.standard_normal(800)
    assert first_input_index(t, rippling) is None
    noisy = 0.01 * rng.standard_normal(800)
    assert first_input_index(t, noisy) is None
    x = lon_flight()["de"].copy()
    x[5] = np.nan
    assert first_input_index(t, x) is None


def test_first_input_accepts_jax_arrays():
    c = lon_flight()
    assert abs(first_input_index(jnp.asarray(c["t"]), jnp.asarray(c["de"])) - 200) <= 1


def test_smoothing_removes_ripple():
    c = lon_flight(ripple=0.05, noise=0.0, amp=0.0)
    y = smooth_input(c["t"], c["de"])
    assert np.max(np.abs(y - LON_TRIM["de"])) < 0.05 * 0.05
    assert np.max(np.abs(c["de"] - LON_TRIM["de"])) > 0.04  # the raw input does ripple


def test_rudder_manoeuvre_uses_dr():
    c = lat_flight(t_input=1.5)
    assert input_column(c, c["t"]) == "dr"
    assert first_input_index(c["t"], c["de"]) is None
    assert abs(first_input_index(c["t"], c["dr"]) - 300) <= 1
    c["ramp"] = c["t"].copy()
    trim = estimate_trim(c, c["t"])
    # the quiet start is the 1.5 s before the rudder doublet, not the 0.2 s fallback
    assert trim["ramp0"] == pytest.approx(np.mean(c["t"][:300]), abs=2 * 0.005)
    for col in ("v", "p", "r", "phi", "psi", "dr"):
        assert trim[col + "0"] == pytest.approx(LAT_TRIM[col], abs=1e-3)


def test_elevator_manoeuvre_uses_de():
    c = lon_flight()
    c["dr"] = 0.01 * np.random.default_rng(0).standard_normal(c["t"].shape[0])
    assert input_column(c, c["t"]) == "de"


def test_estimate_trim_recovers_the_trim():
    c = lon_flight(t_input=1.3, shape="step")
    trim = estimate_trim(c, c["t"])
    assert "t0" not in trim
    assert set(trim) == {k + "0" for k in c if k != "t"}
    for col in ("u", "w", "theta", "q", "de"):
        assert trim[col + "0"] == pytest.approx(LON_TRIM[col], abs=1e-3)
    # a mean over the whole flight (including the response) would be off
    assert abs(np.mean(c["theta"]) - LON_TRIM["theta"]) > 5e-3


def test_estimate_trim_window_ends_at_first_input():
    c = lon_flight(t_input=1.0)
    c["ramp"] = c["t"].copy()
    trim = estimate_trim(c, c["t"])
    assert trim["ramp0"] == pytest.approx(np.mean(c["t"][:200]), abs=2 * 0.005)
    trim = estimate_trim(c, c["t"], first_input=100)
    assert trim["ramp0"] == pytest.approx(np.mean(c["t"][:100]))


@pytest.mark.parametrize("case", ["early input", "no input column", "no input"])
def test_estimate_trim_falls_back_to_first_02_s(case):
    c = lon_flight(t_input=0.1)
    if case == "no input column":
        del c["de"]
    elif case == "no input":
        c["de"] = np.full_like(c["t"], 0.05)
    c["ramp"] = c["t"].copy()
    trim = estimate_trim(c, c["t"])
    assert trim["ramp0"] == pytest.approx(np.mean(c["t"][:40]))  # 0.2 s at 200 Hz
    assert trim["u0"] == pytest.approx(np.mean(c["u"][:40]))


def test_estimate_trim_skips_non_finite_columns():
    c = lon_flight()
    c["bad"] = np.full_like(c["t"], np.nan)
    trim = estimate_trim(c, c["t"])
    assert "bad0" not in trim and "u0" in trim
