"""Zero-phase Butterworth filters in the frequency domain (fwid.decomposition._filters)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal as ss

import fwid  # noqa: F401  (turns on float64)
from fwid import InputError
from fwid.decomposition import highpass, lowpass, squared_gain

DT = 1 / 200
N = 1000
T = np.arange(N) * DT


def _test_signal(seed=0):
    rng = np.random.default_rng(seed)
    return (
        0.8 * np.sin(2 * np.pi * 1.0 * T + 0.2)
        + 0.3 * np.sin(2 * np.pi * 4.7 * T)
        + 0.5 * np.sin(2 * np.pi * 12.5 * T + 0.3)
        + 0.2 * np.sin(2 * np.pi * 37.0 * T + 1.0)
        + 0.3 * T
        + 0.1 * rng.standard_normal(N)
    )


@pytest.mark.parametrize("order", [2, 4, 8])
@pytest.mark.parametrize("cutoff", [5.0, 40.0])
def test_equals_sosfiltfilt_with_full_odd_padding(order, cutoff):
    # Same edge extension (odd reflection, n - 1 samples) => identical everywhere, ends included.
    x = _test_signal()
    sos_lp = ss.butter(order, cutoff, fs=1 / DT, output="sos")
    sos_hp = ss.butter(order, cutoff, "highpass", fs=1 / DT, output="sos")
    ref_lp = ss.sosfiltfilt(sos_lp, x, padtype="odd", padlen=N - 1)
    ref_hp = ss.sosfiltfilt(sos_hp, x, padtype="odd", padlen=N - 1)
    lp = lowpass(x, DT, cutoff, order=order, pad="odd")
    hp = highpass(x, DT, cutoff, order=order, pad="odd")
    np.testing.assert_allclose(lp, ref_lp, rtol=0, atol=1e-9)
    np.testing.assert_allclose(hp, ref_hp, rtol=0, atol=1e-9)


def test_odd_lengths_and_nyquist_bin():
    # Lengths whose padded FFT length puts pi k / m just above pi / 2 at the Nyquist bin.
    for n in (899, 901):
        x = _test_signal()[:n]
        sos = ss.butter(4, 5.0, fs=1 / DT, output="sos")
        ref = ss.sosfiltfilt(sos, x, padtype="odd", padlen=n - 1)
        np.testing.assert_allclose(lowpass(x, DT, 5.0, pad="odd"), ref, rtol=0, atol=1e-9)


@pytest.mark.parametrize("pad", ["hybrid", "odd"])
@pytest.mark.parametrize("order,cutoff", [(4, 5.0), (4, 40.0), (6, 5.0)])
def test_matches_filtfilt_in_the_interior(order, cutoff, pad):
    # Requirement (5): default scipy filtfilt (short padding); they agree away from the ends.
    x = _test_signal(1)
    amplitude = np.max(np.abs(x))
    b, a = ss.butter(order, cutoff, fs=1 / DT)
    ref = ss.filtfilt(b, a, x)
    ours = np.asarray(lowpass(x, DT, cutoff, order=order, pad=pad))
    k = int(1.0 / DT)
    assert np.max(np.abs(ours - ref)[k:-k]) < 1e-3 * amplitude
    b, a = ss.butter(order, cutoff, "highpass", fs=1 / DT)
    ref = ss.filtfilt(b, a, x)
    ours = np.asarray(highpass(x, DT, cutoff, order=order, pad=pad))
    assert np.max(np.abs(ours - ref)[k:-k]) < 1e-3 * amplitude


@pytest.mark.parametrize("order", [1, 4, 6])
def test_squared_gain_is_butterworth_magnitude_squared(order):
    freqs = np.linspace(0.0, 0.5 / DT, 301)
    sos = ss.butter(order, 5.0, fs=1 / DT, output="sos")
    _, h = ss.sosfreqz(sos, worN=freqs, fs=1 / DT)
    gain = squared_gain(freqs, DT, 5.0, order=order)
    np.testing.assert_allclose(gain, np.abs(h) ** 2, atol=1e-10)
    analogue = squared_gain(freqs, DT, 5.0, order=order, prewarp=False)
    np.testing.assert_allclose(analogue, 1 / (1 + (freqs / 5.0) ** (2 * order)), atol=1e-12)


def test_lowpass_plus_highpass_is_identity():
    x = _test_signal(2)
    total = lowpass(x, DT, 5.0, order=6) + highpass(x, DT, 5.0, order=6)
    np.testing.assert_allclose(total, x, rtol=0, atol=1e-12)


def test_zero_phase_no_lag():
    # Requirement (4): a 1 Hz sine through the 5 Hz low-pass keeps its phase.
    x = np.sin(2 * np.pi * 1.0 * T + 0.7)
    y = np.asarray(lowpass(x, DT, 5.0))
    basis = np.stack([np.sin(2 * np.pi * T), np.cos(2 * np.pi * T)], axis=1)
    k = int(0.5 / DT)
    coef, *_ = np.linalg.lstsq(basis[k:-k], y[k:-k], rcond=None)
    phase = np.arctan2(coef[1], coef[0])
    gain = float(squared_gain(1.0, DT, 5.0))
    assert abs(phase - 0.7) < 1e-5  # a causal order-4 filter lags by ~0.3 rad here
    assert abs(np.hypot(*coef) - gain) < 1e-6
    # ... and the peak is not shifted by a single sample.
    lag = np.argmax(np.correlate(y[k:-k], x[k:-k], "full")) - (N - 2 * k - 1)
    assert lag == 0


@pytest.mark.parametrize("pad", ["hybrid", "odd"])
def test_straight_line_and_slow_signal_do_not_ring_at_the_ends(pad):
    line = 2.0 - 0.7 * T
    np.testing.assert_allclose(lowpass(line, DT, 5.0, pad=pad), line, atol=1e-10)
    np.testing.assert_allclose(highpass(line, DT, 5.0, pad=pad), 0.0, atol=1e-10)
    # Ends that do not match (a circular FFT filter would ring here).
    slow = 1.0 + 0.5 * np.sin(2 * np.pi * 0.4 * T + 0.3) + 0.2 * T
    assert np.max(np.abs(lowpass(slow, DT, 5.0, pad=pad) - slow)) < 2e-3


def test_hybrid_edges_follow_the_slow_part_under_a_large_oscillation():
    # Odd reflection about an end sample that the wing beat has pushed away from the cycle
    # average drags the low-passed signal towards that sample; the hybrid extension does not.
    slow = 0.2 * np.sin(2 * np.pi * 0.7 * T + 0.5) + 0.1 * T
    x = slow + 0.3 * np.sin(2 * np.pi * 12.3 * T + 1.2) + 0.1 * np.sin(2 * np.pi * 24.6 * T)
    k = int(0.1 / DT)
    errors = {
        pad: np.abs(np.asarray(lowpass(x, DT, 5.0, order=6, pad=pad)) - slow)
        for pad in ("odd", "even", "hybrid")
    }
    assert np.max(errors["hybrid"][k:-k]) < 0.5 * np.max(errors["odd"][k:-k])
    assert np.max(errors["hybrid"][k:-k]) < 0.02  # 7 % of the wing beat's amplitude
    with pytest.raises(InputError, match="pad"):
        lowpass(x, DT, 5.0, pad="zero")


def test_hybrid_end_value_is_the_slow_part_s_level_not_the_end_sample():
    # A record's last samples carry an error of their own (loads from tracked motion are
    # one-sided there): the low-passed value at the end follows the slow part's level near
    # the end, not the end sample, while a slow signal's curvature costs little.
    slow = 1.0 + 0.5 * np.sin(2 * np.pi * 0.4 * T + 0.3) + 0.2 * T
    bump = np.zeros_like(T)
    bump[-3:] = [0.3, 0.6, 1.0]
    end = float(np.asarray(lowpass(slow + bump, DT, 5.0, order=6))[-1]) - slow[-1]
    odd = float(np.asarray(lowpass(slow + bump, DT, 5.0, order=6, pad="odd"))[-1]) - slow[-1]
    assert abs(end) < 0.35 * abs(odd)
    assert abs(end) < 0.3


def test_channels_jit_vmap():
    x = np.stack([_test_signal(s) for s in range(3)])
    y = lowpass(x, DT, 5.0)
    assert y.shape == x.shape
    for row in range(3):
        np.testing.assert_allclose(y[row], lowpass(x[row], DT, 5.0), atol=1e-13)
    jitted = jax.jit(lambda v, c: lowpass(v, DT, c, order=4))
    np.testing.assert_allclose(jitted(x, 5.0), y, atol=1e-13)
    cutoffs = jnp.array([3.0, 5.0, 8.0])
    batched = jax.vmap(lambda c: highpass(x[0], DT, c))(cutoffs)
    for i, c in enumerate([3.0, 5.0, 8.0]):
        np.testing.assert_allclose(batched[i], highpass(x[0], DT, c), atol=1e-13)


@pytest.mark.parametrize("fn,order", [(lowpass, 4), (highpass, 6)])
def test_gradient_wrt_cutoff_matches_finite_difference(fn, order):
    # Requirement (6).
    x = jnp.asarray(_test_signal(3))
    weights = jnp.asarray(np.cos(2 * np.pi * 0.37 * T))

    def scalar(c):
        y = fn(x, DT, c, order=order)
        return jnp.sum(y**2) + jnp.sum(weights * y)

    value_and_grad = jax.jit(jax.value_and_grad(scalar))  # one compilation serves both
    grad = value_and_grad(5.0)[1]
    h = 1e-4
    fd = (value_and_grad(5.0 + h)[0] - value_and_grad(5.0 - h)[0]) / (2 * h)
    assert abs(grad) > 1e-3
    assert abs(grad - fd) <= 1e-5 * abs(fd)


@pytest.mark.parametrize("cutoff", [0.0, -1.0, 100.0, 150.0])
def test_bad_cutoff_raises(cutoff):
    with pytest.raises(InputError, match="Nyquist"):
        lowpass(_test_signal(), DT, cutoff)
