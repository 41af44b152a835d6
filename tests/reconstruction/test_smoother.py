"""Problems of several lengths padded to one (`smooth_batch(..., lengths=...)`) give what
each gives alone: the noise levels chosen and the smoothed samples."""

import numpy as np

from fwid.reconstruction._model import phase_of
from fwid.reconstruction._smoother import _active_window, smooth_batch


def _problem(N, dt, rng):
    t = np.arange(N) * dt
    f = np.full(N, 12.0)
    z = (0.02 * np.sin(2 * np.pi * 0.7 * t) + 1e-3 * np.sin(2 * np.pi * 12.0 * t))[:, None]
    z = z + 1e-4 * rng.standard_normal((N, 1))
    mask = rng.random(N) > 0.05
    mask[0] = True
    return z, mask, *phase_of(f, dt)


def test_padded_batch_equals_each_alone():
    dt, rng = 0.005, np.random.default_rng(3)
    lengths = [1300, 1180]
    probs = [_problem(N, dt, rng) for N in lengths]
    n = 1536

    def pad(x, fill):
        return np.concatenate([x, np.full((n - len(x),) + x.shape[1:], fill, dtype=x.dtype)])

    z, mask, phase, omega = (np.stack([pad(p[i], f) for p in probs])
                             for i, f in enumerate((np.nan, False, 0.0, np.nan)))
    both = smooth_batch(z, mask, phase, omega, dt, lengths=np.array(lengths))
    for j, (N, p) in enumerate(zip(lengths, probs)):
        alone = smooth_batch(p[0][None], p[1][None], p[2][None], p[3][None], dt)
        assert alone.params[0] == both.params[j]
        for k in ("pos", "vel", "acc"):
            ref = getattr(alone, k)[0]
            got = getattr(both, k)[j, :N]
            assert np.max(np.abs(got - ref)) <= 1e-9 * np.max(np.abs(ref))
        assert abs(both.sigma[j] - alone.sigma[0]) <= 1e-9 * alone.sigma[0]


def _manoeuvre(N, dt, rng):
    """A pitch-like record: a 3-s manoeuvre at the start, then steady flapping flight (the
    flapping as large throughout), 0.15 deg noise; returns the data and the true rate."""
    t = np.arange(N) * dt
    env = np.exp(-(((t - 2.0) / 0.8) ** 2))
    slow = 0.15 * np.sin(2 * np.pi * 0.8 * (t - 2.0)) * env
    dslow = 0.15 * env * (2 * np.pi * 0.8 * np.cos(2 * np.pi * 0.8 * (t - 2.0))
                          - 2 * (t - 2.0) / 0.8**2 * np.sin(2 * np.pi * 0.8 * (t - 2.0)))
    w = 2 * np.pi * 12.0
    flap = 3e-3 * np.sin(w * t) + 1e-3 * np.sin(2 * w * t + 0.4)
    dflap = 3e-3 * w * np.cos(w * t) + 2e-3 * w * np.cos(2 * w * t + 0.4)
    z = (slow + flap + np.deg2rad(0.15) * rng.standard_normal(N))[:, None]
    return z, np.ones(N, bool), *phase_of(np.full(N, 12.0), dt), dslow + dflap


def test_long_take_smoothed_as_well_as_short():
    """A manoeuvre followed by a minute of steady flight is smoothed as well as the same
    manoeuvre in a short take: the noise levels suit the manoeuvre, not the steady part
    (both in one padded batch, one compiled program)."""
    dt, lengths = 0.01, np.array([600, 6000])
    probs = [_manoeuvre(N, dt, np.random.default_rng(5)) for N in lengths]
    n = lengths.max()

    def pad(x, fill):
        return np.concatenate([x, np.full((n - len(x),) + x.shape[1:], fill, dtype=x.dtype)])

    z, mask, phase, omega = (np.stack([pad(p[i], f) for p in probs])
                             for i, f in enumerate((np.nan, False, 0.0, np.nan)))
    sm = smooth_batch(z, mask, phase, omega, dt, lengths=lengths)
    err = []
    for j, p in enumerate(probs):
        e = sm.vel[j, :400, 0] - p[4][:400]  # the first 4 s: the manoeuvre
        err.append(np.sqrt(np.mean(e**2)) / np.ptp(p[4][:400]))
        assert abs(sm.sigma[j] - np.deg2rad(0.15)) < 0.2 * np.deg2rad(0.15)  # the noise found
    assert err[0] < 0.05
    assert err[1] < 1.5 * err[0], err


def test_window_of_a_long_take_sits_on_its_manoeuvre():
    """In 90 s of steady flapping flight with one manoeuvre (at 60 s), the
    noise levels are chosen on the manoeuvre: the window's activity is the cycle-averaged
    motion's, not the flapping's or the noise's, which are as large everywhere (a window in
    the steady part over-smooths the manoeuvre: 4-5 % errors of the slow states)."""
    dt, N, centre = 0.005, 18000, 60.0
    t = np.arange(N) * dt
    slow = 0.15 * np.sin(2 * np.pi * 0.8 * (t - centre)) * np.exp(-(((t - centre) / 0.8) ** 2))
    w = 2 * np.pi * 12.5
    flap = 3e-3 * np.sin(w * t) + 1e-3 * np.sin(2 * w * t + 0.4)
    z = slow + flap + np.deg2rad(0.15) * np.random.default_rng(1).standard_normal(N)
    _, omega = phase_of(np.full(N, 12.5), dt)
    idx = _active_window(z[None, :, None], np.zeros((1, N, 1)), np.ones((1, N), bool), dt,
                         omega=omega[None])
    assert t[idx[0, 0]] < centre - 1.0 and t[idx[0, -1]] > centre + 1.0


def _slow_records(M, N, dt, rng):
    """`M` records of random slow motion (five sines, 0.2-2 Hz) with a 12 Hz wing beat and
    0.4 mm noise; returns the data and the slow part's true acceleration `(M, N)`."""
    t = np.arange(N) * dt
    f = rng.uniform(0.2, 2.0, (M, 5, 1))
    amp = 2e-3 * rng.standard_normal((M, 5, 1)) / f
    ph = rng.uniform(0, 2 * np.pi, (M, 5, 1))
    slow = np.sum(amp * np.sin(2 * np.pi * f * t + ph), 1)
    acc = -np.sum(amp * (2 * np.pi * f) ** 2 * np.sin(2 * np.pi * f * t + ph), 1)
    z = slow + 5e-4 * np.sin(2 * np.pi * 12.0 * t) + 4e-4 * rng.standard_normal((M, N))
    phase, omega = phase_of(np.full(N, 12.0), dt)
    return z[..., None], np.ones((M, N), bool), np.tile(phase, (M, 1)), np.tile(omega, (M, 1)), acc


def test_ends_held_to_the_take_s_own_acceleration():
    """The slow acceleration at a short take's first and last samples, where the motion is
    seen from one side only, is nearer the truth with the ends' prior (`ends=True`) than with
    the diffuse start alone, and the middle of the take does not move."""
    dt, rng = 0.005, np.random.default_rng(11)
    z, mask, phase, omega, acc = _slow_records(96, 900, dt, rng)
    err = {}
    for ends in (False, True):
        sm = smooth_batch(z, mask, phase, omega, dt, ends=ends)
        err[ends] = sm.slow[:, :, 2, 0] - acc
    edge = np.r_[0:10, 890:900]
    rms = {k: np.sqrt(np.mean(e[:, edge] ** 2)) for k, e in err.items()}
    assert rms[True] < 0.95 * rms[False]  # 0.90 here; 0.87-0.92 over seeds 11-13
    mid = slice(300, 600)
    assert np.max(np.abs(err[True][:, mid] - err[False][:, mid])) < 0.01 * np.std(acc)
