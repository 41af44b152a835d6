"""Flapping frequency estimate, flapping phase and the check of a measured `f` column."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid  # noqa: F401  (turns on float64)
from fwid import FlightDataError
from fwid.decomposition import check_flapping_frequency, estimate_flapping_frequency, flapping_phase

DT = 1 / 200
N = 800  # 4 s: FFT bins 0.25 Hz apart
T = np.arange(N) * DT


def _flapping_signal(phase, rng, noise=0.05):
    """A force-like signal: three harmonics of the wing beat on slow body motion, plus noise."""
    return (
        0.3 * np.sin(phase + rng.uniform(0, 2 * np.pi))
        + 0.12 * np.sin(2 * phase + 1.0)
        + 0.05 * np.sin(3 * phase + 2.0)
        + 0.5 * np.sin(2 * np.pi * 0.8 * T)
        + 0.2 * T
        + noise * rng.standard_normal(N)
    )


def test_constant_frequency_within_0p05_hz():
    rng = np.random.default_rng(0)
    freqs = np.linspace(10.6, 14.4, 9)
    signals = np.stack([_flapping_signal(2 * np.pi * f * T, rng) for f in freqs])
    estimates = np.asarray(estimate_flapping_frequency(signals, DT))  # channels at once
    assert estimates.shape == freqs.shape
    assert np.max(np.abs(estimates - freqs)) < 0.05


def test_drifting_frequency_gives_its_mean():
    rng = np.random.default_rng(1)
    f = 11.5 + (13.2 - 11.5) * T / T[-1]
    phase = np.asarray(flapping_phase(f, DT))
    estimate = float(estimate_flapping_frequency(_flapping_signal(phase, rng), DT))
    assert abs(estimate - f.mean()) < 0.05


def test_dominant_second_harmonic_is_not_taken_for_the_fundamental():
    rng = np.random.default_rng(2)
    x = 0.1 * np.sin(2 * np.pi * 12.2 * T) + 0.3 * np.sin(2 * np.pi * 24.4 * T)
    x = x + 0.02 * rng.standard_normal(N)
    assert abs(float(estimate_flapping_frequency(x, DT)) - 12.2) < 0.05


def test_estimate_vmap():
    # (The estimate is jitted inside, with `dt` traced, so every call also checks jit.)
    rng = np.random.default_rng(3)
    x = np.stack([_flapping_signal(2 * np.pi * f * T, rng) for f in (11.0, 13.0)])
    batched = jax.vmap(lambda v: estimate_flapping_frequency(v, DT))(x)
    np.testing.assert_allclose(batched, [estimate_flapping_frequency(v, DT) for v in x])


def test_flapping_phase_exact_for_linear_frequency():
    f = 11.5 + 0.4 * T
    phase = flapping_phase(f, DT, phase0=0.3)
    np.testing.assert_allclose(phase, 0.3 + 2 * np.pi * (11.5 * T + 0.2 * T**2), atol=1e-10)


def test_flapping_phase_for_oscillating_frequency():
    w = 2 * np.pi * 0.5
    f = 12.0 + 0.8 * np.sin(w * T)
    exact = 2 * np.pi * (12.0 * T + 0.8 * (1 - np.cos(w * T)) / w)
    phase = flapping_phase(f, DT)
    assert np.max(np.abs(phase - exact)) < 1e-4  # trapezoid: O(dt^2)
    # Constant f: exactly Eq. (12)'s 2 pi f t; batched channels along leading axes.
    batch = flapping_phase(np.stack([np.full(N, 12.5), f]), DT, phase0=jnp.array([0.0, 0.0]))
    np.testing.assert_allclose(batch[0], 2 * np.pi * 12.5 * T, atol=1e-10)
    np.testing.assert_allclose(batch[1], phase, atol=1e-12)
    grad = jax.grad(lambda c: flapping_phase(c * f, DT)[-1])(1.0)
    np.testing.assert_allclose(grad, phase[-1], rtol=1e-12)


def test_check_flapping_frequency():
    rng = np.random.default_rng(4)
    f = 12.4 + 0.3 * np.sin(2 * np.pi * 0.25 * T)
    x = _flapping_signal(np.asarray(flapping_phase(f, DT)), rng)
    message = check_flapping_frequency(f, x, DT, name="lon_0.csv")
    assert message.startswith("lon_0.csv: ") and "Hz" in message
    with pytest.raises(FlightDataError, match="rad/s"):
        check_flapping_frequency(2 * np.pi * f, x, DT)
    with pytest.raises(FlightDataError, match="harmonic"):
        check_flapping_frequency(2 * f, x, DT)
    with pytest.raises(FlightDataError, match="apart"):
        check_flapping_frequency(f * 1.2, x, DT)
    with pytest.raises(FlightDataError, match="positive"):
        check_flapping_frequency(np.where(T > 1, f, -1.0), x, DT)
