"""`flap-frequency`: the cycle-averaged loads follow the slow variation of the flapping
frequency `f` (thrust grows with it), which Eqs. (1-6) leave out: `df` and `df^2` (`df` the
cycle-averaged `f` minus its flight median), at once or through a first-order lag from
`FREQUENCY_LAGS`."""

from __future__ import annotations

import numpy as np

from .._signals import Signals
from ._effect import Effect, slow_of
from ._filters import lagged

#: Time constants [s] tried (0: none).
FREQUENCY_LAGS = (0.0, 0.1, 0.2, 0.4)


def frequency_deviation(f: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """The flapping frequency minus its median over the flight, through a first-order lag
    `tau` (0: none)."""
    df = f - np.median(f)
    return lagged(df, dt, "lag", tau) if tau else df


def _columns(s: Signals, load, tau, h, dh):
    df = frequency_deviation(slow_of(s, "f"), s.dt, tau)
    return np.stack([df, df * df], axis=1)


EFFECT = Effect(
    "flap-frequency",
    "the cycle-averaged loads follow the flapping frequency",
    "averaged",
    _columns,
    FREQUENCY_LAGS,
    labels=lambda load: ("f", "f"),
    crosses_axes=True,
)
