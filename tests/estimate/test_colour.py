"""Residual colour at the data's bandwidth (fwid/estimate/_colour.py), against numpy."""

import jax.numpy as jnp
import numpy as np
from scipy.signal import butter, filtfilt

from fwid.estimate._colour import bandwidth_lag, colour_at_bandwidth
from fwid.estimate._uncertainty import lag1_autocorrelation

FS = 200.0
N = 1600


def _lowpassed(x, cutoff=5.0):
    b, a = butter(4, cutoff / (FS / 2))
    return filtfilt(b, a, x, axis=0)


def _numpy_colour(v, z):
    """Independent: the 99 % power frequency of the Hann-windowed diff(z) from numpy's FFT,
    then the largest direct lag sum over k .. 3k."""
    out = []
    for j in range(v.shape[1]):
        d = np.diff(z[:, j])
        d = (d - d.mean()) * np.hanning(len(d))
        P = np.abs(np.fft.rfft(d, n=2 * len(z))) ** 2
        f = np.fft.rfftfreq(2 * len(z))
        fb = f[np.argmax(np.cumsum(P) / P.sum() >= 0.99)]
        k = max(1, int(round(0.5 / fb)))
        out.append((k, max(np.sum(v[tau:, j] * v[:-tau, j]) for tau in range(k, 3 * k + 1))
                    / np.sum(v[:, j] ** 2)))
    return out


def test_prefiltered_measurement_noise_is_white_at_the_data_bandwidth():
    """Noise low-passed at 5 Hz and sampled at 200 Hz (the DelFly demo's cycle-averaged
    flights, step inputs): autocorrelation ~0.99 at one sample, below 0.3 at the data's
    bandwidth, a lag of about 1 / (2 * 5 Hz) = 20 samples; white noise keeps a lag of one
    sample."""
    rng = np.random.default_rng(0)
    t = np.arange(N) / FS
    signal = np.column_stack([np.sign(np.sin(2 * np.pi * 0.25 * t)),
                              np.sign(np.sin(2 * np.pi * 0.4 * t))])
    z = _lowpassed(signal + 0.05 * rng.standard_normal((N, 2)))
    v = _lowpassed(0.05 * rng.standard_normal((N, 2)))
    mask = jnp.ones(N)
    assert np.all(np.asarray(lag1_autocorrelation(jnp.asarray(v), mask)) > 0.98)
    k = np.asarray(bandwidth_lag(jnp.asarray(z), mask))
    assert np.all((k >= 16) & (k <= 30)), k
    c = np.asarray(colour_at_bandwidth(jnp.asarray(v), jnp.asarray(z), mask))
    assert np.all(c < 0.3), c
    ref = _numpy_colour(v, z)
    np.testing.assert_array_equal(k, [kk for kk, _ in ref])
    np.testing.assert_allclose(c, [cc for _, cc in ref], atol=1e-12)
    # raw white noise: the data reach Nyquist, the lag is one sample
    w = rng.standard_normal((N, 2))
    assert np.all(np.asarray(bandwidth_lag(jnp.asarray(signal + w), mask)) == 1)


def test_model_error_is_coloured_at_the_data_bandwidth_and_padding_is_ignored():
    """Data whose content ends at 0.7 Hz (a sine; lag k = half its period, 0.5 / 0.88 Hz):
    a slow missing effect (0.1 Hz) and one at the data's top frequency (0.7 Hz, negatively
    correlated at k itself, back near 1 at 2k) are both coloured; the pre-filtered noise is
    not. Padding with a zero mask (as in a batch) changes nothing."""
    rng = np.random.default_rng(1)
    t = np.arange(N) / FS
    z = _lowpassed(np.sin(2 * np.pi * 0.7 * t)[:, None] + 0.05 * rng.standard_normal((N, 1)))
    k = int(bandwidth_lag(jnp.asarray(z), jnp.ones(N))[0])
    assert 100 <= k <= 130, k
    noise = _lowpassed(0.02 * rng.standard_normal((N, 1)))
    assert float(colour_at_bandwidth(jnp.asarray(noise), jnp.asarray(z), jnp.ones(N))[0]) < 0.3
    fast = 0.05 * np.sin(2 * np.pi * 0.7 * t)[:, None] + noise
    assert np.sum(fast[k:] * fast[:-k]) < 0  # the plain lag-k autocorrelation misses it
    assert float(colour_at_bandwidth(jnp.asarray(fast), jnp.asarray(z), jnp.ones(N))[0]) > 0.6
    v = 0.05 * np.sin(2 * np.pi * 0.1 * t)[:, None] + noise
    c = float(colour_at_bandwidth(jnp.asarray(v), jnp.asarray(z), jnp.ones(N))[0])
    assert c > 0.8
    pad = 300
    zp = np.concatenate([z, np.repeat(z[-1:], pad, 0)])
    vp = np.concatenate([v, np.zeros((pad, 1))])
    mp = jnp.concatenate([jnp.ones(N), jnp.zeros(pad)])
    # the padding only refines the frequency grid of the spectrum: k within 3 %
    assert abs(int(bandwidth_lag(jnp.asarray(zp), mp)[0]) - k) <= 0.03 * k
    cp = float(colour_at_bandwidth(jnp.asarray(vp), jnp.asarray(zp), mp)[0])
    assert abs(cp - c) < 0.02 and cp > 0.8
    # a padded white record: still white
    wp = np.concatenate([rng.standard_normal((N, 1)), np.zeros((pad, 1))])
    assert abs(float(colour_at_bandwidth(jnp.asarray(wp), jnp.asarray(zp), mp)[0])) < 0.2
