"""`turbulence` (outside the catalogue), form `gusts`: wind gusts `ug, wg, vg` (white noise
through a first-order filter at `GUST_BANDWIDTH` Hz, RMS `s * GUST_RMS` m/s) act through the
vehicle's own velocity derivatives, `dF = Fx [ug, wg, vg]`: unmeasured loads, no new
physics."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from ._form import Form

#: Gust RMS [m/s] at strength 1 and the bandwidth [Hz] of the gust filter.
GUST_RMS = 0.06
GUST_BANDWIDTH = 1.0


class Gusts(Form):
    effect, name = "turbulence", "gusts"
    COEFFICIENTS = {"gust_rms": GUST_RMS}

    def gusts(self, t, seed):
        """Gust velocities `(n, 3)` = `[ug, wg, vg]` at times `t`, drawn from their own
        generator, so the flight's other random draws do not change."""
        rng = np.random.default_rng([seed, 7919])
        h = t[1] - t[0]
        a = np.exp(-2 * np.pi * GUST_BANDWIDTH * h)
        w = rng.standard_normal((len(t), 3)) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal(3)  # g_0: stationary from t = 0
        g = lfilter((1.0,), (1.0, -a), w, axis=0)  # first-order Gauss-Markov: g_k = a g_k-1 + w_k
        return g * self.c["gust_rms"]


TURBULENCE = (Gusts,)
