"""The cycle-averaged / flapping split (Section III.B) on arrays and on `Flight`s."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid  # noqa: F401  (turns on float64)
from fwid import InputError
from fwid.data._flight import Flight
from fwid.decomposition import (
    Decomposition,
    cycle_averaged,
    decompose,
    flapping_part,
    lowpass,
    squared_gain,
)

DT = 1 / 200
N = 1000  # 5 s
T = np.arange(N) * DT
EDGE = int(0.5 / DT)  # "away from the ends"
SIGMA = 0.05
SLOW = (
    0.5 * np.sin(2 * np.pi * 0.3 * T + 0.4)
    + 0.3 * np.sin(2 * np.pi * 1.0 * T + 1.1)
    + 0.2 * np.sin(2 * np.pi * 2.0 * T + 2.0)
    + 0.1 * T
)
HARMONICS = [(12.5, 0.3, 0.2), (25.0, 0.15, 1.3), (37.5, 0.08, 2.9)]  # (Hz, amplitude, phase)
FLAP = sum(a * np.sin(2 * np.pi * f * T + p) for f, a, p in HARMONICS)


def _columns(seed=0):
    rng = np.random.default_rng(seed)
    noise = SIGMA * rng.standard_normal(N)
    return {
        "t": T,
        "slow": SLOW + noise,  # cycle-averaged only, plus white noise
        "noise": noise,
        "both": SLOW + FLAP + 0.01 * rng.standard_normal(N),
        "f": np.full(N, 12.5),
    }


def _amplitudes(x, freqs):
    """Least-squares amplitude of each sinusoid, fitted away from the ends."""
    cols = [g(2 * np.pi * f * T) for f in freqs for g in (np.sin, np.cos)]
    basis = np.stack(cols + [np.ones(N)], axis=1)[EDGE:-EDGE]
    coef, *_ = np.linalg.lstsq(basis, np.asarray(x)[EDGE:-EDGE], rcond=None)
    return np.hypot(coef[0:-1:2], coef[1:-1:2])


def test_parts_add_back_to_the_filtered_signal():
    # Requirement (1).
    cols = _columns()
    parts = decompose(cols, DT)
    assert isinstance(parts, Decomposition)
    assert parts.names == ("slow", "noise", "both")  # t and f skipped
    for k in parts.names:
        filtered = lowpass(cols[k], DT, 40.0, order=4)
        total = parts.averaged[k] + parts.flapping[k]
        np.testing.assert_allclose(total, filtered, rtol=0, atol=1e-12)
        np.testing.assert_allclose(parts.filtered[k], filtered, rtol=0, atol=1e-12)
    assert float(parts.noise_cutoff) == 40.0 and float(parts.split_cutoff) == 5.0
    assert (parts.noise_order, parts.split_order) == (4, 6)


def test_cycle_averaged_signal_leaves_the_flapping_band_empty():
    # Requirement (2): the flapping part of slow motion + white noise is just the noise in the
    # flapping band (its RMS is the noise RMS through |H_40|^2 (1 - |H_5|^2)).
    cols = _columns(1)
    parts = decompose(cols, DT)
    freqs = np.linspace(0.0, 0.5 / DT, 200001)
    gain = squared_gain(freqs, DT, 40.0, order=4) * (1 - squared_gain(freqs, DT, 5.0, order=6))
    band_rms = SIGMA * np.sqrt(np.mean(np.asarray(gain) ** 2))
    flapping = np.asarray(parts.flapping["slow"])[EDGE:-EDGE]
    assert 0.9 < np.sqrt(np.mean(flapping**2)) / band_rms < 1.1
    # What the slow signal itself leaves there (flapping parts are linear in the input).
    leak = flapping - np.asarray(parts.flapping["noise"])[EDGE:-EDGE]
    assert np.sqrt(np.mean(leak**2)) < 0.005 * band_rms
    assert np.max(np.abs(leak)) < 0.02 * band_rms


def test_flapping_harmonics_are_separated_from_slow_motion():
    # Requirement (3).
    parts = decompose(_columns(2), DT)
    freqs = [f for f, _, _ in HARMONICS]
    truth = np.array([a for _, a, _ in HARMONICS])
    recovered = _amplitudes(parts.flapping["both"], freqs)
    # The first two harmonics come through within a few per cent ...
    np.testing.assert_allclose(recovered[:2], truth[:2], rtol=0.03)
    # ... all three exactly as attenuated by the zero-phase filters (the 40 Hz noise filter takes
    # 37 % of a 37.5 Hz third harmonic: the paper's compromise, Section III.B).
    gains = squared_gain(np.array(freqs), DT, 40.0, order=4)
    gains = gains * (1 - squared_gain(np.array(freqs), DT, 5.0, order=6))
    np.testing.assert_allclose(recovered, truth * np.asarray(gains), rtol=0.01)
    # The cycle-averaged part is the slow signal.
    error = np.asarray(parts.averaged["both"]) - SLOW
    assert np.max(np.abs(error[EDGE:-EDGE])) < 0.01 * np.max(np.abs(SLOW))
    # No phase shift of the flapping part either.
    assert np.max(np.abs(np.asarray(parts.flapping["both"]) - FLAP)[EDGE:-EDGE]) < 0.05


def test_jit_and_gradient_wrt_the_cutoffs():
    cols = {k: jnp.asarray(v) for k, v in _columns(3).items()}

    def scalar(split, noise):
        parts = decompose(cols, DT, noise_cutoff=noise, split_cutoff=split)
        averaged, flapping = parts.averaged["both"], parts.flapping["slow"]
        return jnp.sum(averaged**2) + jnp.sum(flapping * cols["noise"])

    value_and_grad = jax.jit(jax.value_and_grad(scalar, argnums=(0, 1)))
    value, grads = value_and_grad(5.0, 40.0)
    np.testing.assert_allclose(value, scalar(5.0, 40.0), rtol=1e-12)
    # Requirement (6): d/d(split cut-off) and d/d(noise cut-off) against central differences.
    h = 1e-4
    fd_split = (value_and_grad(5.0 + h, 40.0)[0] - value_and_grad(5.0 - h, 40.0)[0]) / (2 * h)
    fd_noise = (value_and_grad(5.0, 40.0 + h)[0] - value_and_grad(5.0, 40.0 - h)[0]) / (2 * h)
    assert abs(grads[0] - fd_split) <= 1e-5 * abs(fd_split)
    assert abs(grads[1] - fd_noise) <= 1e-5 * abs(fd_noise)


def test_batched_columns():
    cols = _columns(4)
    batch = {k: np.stack([cols[k], 2 * cols[k]]) for k in ("slow", "both")}
    parts = decompose(batch, DT)
    assert parts.averaged["both"].shape == (2, N)
    np.testing.assert_allclose(parts.flapping["both"][1], 2 * parts.flapping["both"][0], atol=1e-12)


def test_noise_filter_skipped_and_errors():
    cols = _columns(5)
    none = decompose(cols, DT, noise_cutoff=None)
    assert none.noise_cutoff is None
    np.testing.assert_allclose(none.filtered["both"], cols["both"], atol=1e-12)
    above = decompose(cols, DT, noise_cutoff=150.0)  # above Nyquist (100 Hz): nothing to remove
    assert above.noise_cutoff is None
    with pytest.raises(InputError, match="same shape"):
        decompose({"a": T, "b": T[:-1]}, DT)
    with pytest.raises(InputError, match="below the noise cut-off"):
        decompose(cols, DT, split_cutoff=45.0)
    with pytest.raises(InputError, match="Nyquist"):
        decompose(cols, DT, split_cutoff=120.0)


def _flight():
    rng = np.random.default_rng(6)
    ripple = 0.02 * np.sin(2 * np.pi * 12.5 * T)
    de = np.where(T > 1.0, -0.1, 0.0) + ripple
    columns = {
        "q": SLOW + 0.3 * FLAP,
        "de": de,
        "X": 0.1 * SLOW + FLAP + 0.01 * rng.standard_normal(N),
        "f": 12.5 + 0.1 * np.sin(T),
    }
    trim = {"q0": jnp.asarray(0.05), "u0": jnp.asarray(4.0), "de0": jnp.asarray(0.0)}
    return Flight(
        t=jnp.asarray(T),
        columns={k: jnp.asarray(v) for k, v in columns.items()},
        trim=trim,
        vehicle=None,
        name="lon_0.csv",
    ), ripple


def test_flight_conveniences():
    flight, ripple = _flight()
    averaged = cycle_averaged(flight)
    flapping = flapping_part(flight)
    parts = decompose(flight.columns, flight.dt)
    for out in (averaged, flapping):
        assert out.t is flight.t and out.name == flight.name
        np.testing.assert_array_equal(out["f"], flight["f"])  # carried as is
        assert set(out.columns) == set(flight.columns)
    for k in ("q", "de", "X"):
        np.testing.assert_allclose(averaged[k], parts.averaged[k], atol=1e-14)
        np.testing.assert_allclose(flapping[k], parts.flapping[k], atol=1e-14)
    # The elevator ripple stays out of the cycle-averaged input and forms the flapping part
    # (compared with the decomposition of the elevator step alone: the split is linear).
    step = decompose({"de": flight["de"] - ripple}, flight.dt)
    ripple_in_averaged = np.asarray(averaged["de"] - step.averaged["de"])[EDGE:-EDGE]
    assert np.max(np.abs(ripple_in_averaged)) < 2e-3 * 0.02  # edge transient, 0.5 s in
    ripple_in_flapping = np.asarray(flapping["de"] - step.flapping["de"])[EDGE:-EDGE]
    np.testing.assert_allclose(ripple_in_flapping, ripple[EDGE:-EDGE], atol=0.01 * 0.02)
    # Trim: kept for the cycle-averaged flight, zero for the flapping part's columns.
    assert {k: float(v) for k, v in averaged.trim.items()} == {"q0": 0.05, "u0": 4.0, "de0": 0.0}
    assert float(flapping.trim["q0"]) == 0.0 and float(flapping.trim["u0"]) == 4.0
    np.testing.assert_allclose(flapping.perturbation("q"), flapping["q"])
    # Jit through a Flight.
    jitted = jax.jit(lambda fl: cycle_averaged(fl, cutoff=5.0))(flight)
    np.testing.assert_allclose(jitted["q"], averaged["q"], atol=1e-12)
