"""Problems of several lengths padded to one (`smooth_batch(..., lengths=...)`) give what
each gives alone: the noise levels chosen and the smoothed samples."""

import numpy as np

from fwid.reconstruction._model import phase_of
from fwid.reconstruction._smoother import smooth_batch


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
