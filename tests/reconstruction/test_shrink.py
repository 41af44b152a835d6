"""Flapping harmonics below their noise are shrunk toward zero, those well above it kept, and
the derivatives follow the signal."""

import numpy as np

from fwid.reconstruction._model import phase_of
from fwid.reconstruction._shrink import coefficient_variance, shrink_harmonics

DT = 0.005
T = np.arange(0, 4, DT)


def _signal(amps, f):
    ph, om = phase_of(f, DT)
    y = 0.3 * np.sin(2 * np.pi * 0.5 * T)[:, None] + sum(
        a * np.cos(k * ph + 0.3 * k)[:, None] for k, a in enumerate(amps, 1))
    return y, ph, om


def test_noise_level_harmonics_go_and_strong_ones_stay():
    rng = np.random.default_rng(0)
    sigma = 1e-3
    f = 12.0 + 0.3 * np.sin(2 * np.pi * 0.2 * T)  # a frequency that wanders
    clean, ph, om = _signal([1e-2, 3e-3, 0.0], f)
    # what a smoother leaves of white noise at the harmonics: its LS projection on them
    noise = sigma * rng.standard_normal(len(T))
    B = np.stack([g(k * ph) for k in (1, 2, 3) for g in (np.cos, np.sin)], 1)
    left = B @ np.linalg.lstsq(B, noise, rcond=None)[0]
    y = clean + left[:, None]
    var = np.full((3, 1), coefficient_variance(np.array([sigma]), len(T)))
    (out,), g = shrink_harmonics([y], ph, om, var, DT)
    assert g[0, 0] > 0.99 and g[1, 0] > 0.95  # 10 and 3 mm against 0.05 mm of noise
    assert g[2, 0] < 0.5
    # the third harmonic's noise is gone, the others' (a third each) kept
    assert np.std(out - clean) < 0.85 * np.std(y - clean)


def test_derivatives_follow():
    """All of a harmonic removed (noise far above it): what is left of the signal and of its
    two derivatives is the slow motion's, to 3 % of the harmonic's own amplitude."""
    f = np.full(len(T), 12.0)
    ph, _ = phase_of(f, DT)
    w, v = 2 * np.pi * 12.0 * 3, 2 * np.pi * 0.5
    slow = [0.3 * np.sin(v * T), 0.3 * v * np.cos(v * T), -0.3 * v**2 * np.sin(v * T)]
    harm = [1e-3 * np.cos(3 * ph + 0.9), -1e-3 * w * np.sin(3 * ph + 0.9),
            -1e-3 * w**2 * np.cos(3 * ph + 0.9)]
    series = [(a + b)[:, None] for a, b in zip(slow, harm)]
    out, g = shrink_harmonics(series, ph, 2 * np.pi * f, np.full((3, 1), 1.0), DT)
    assert np.all(g == 0)
    s = slice(40, -40)
    for o, sl, h in zip(out, slow, harm):
        assert np.max(np.abs(o[s, 0] - sl[s])) < 0.03 * np.max(np.abs(h))
