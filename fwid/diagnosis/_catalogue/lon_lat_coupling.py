"""`lon-lat-coupling`: the other axis's states and control drive the loads (Eqs. 2 and 5 with
the cross terms the paper leaves out)."""

from __future__ import annotations

import numpy as np

from .._signals import Signals, other
from ._effect import Effect, axis_of, slow_of, variables


def _columns(s: Signals, load, variant, h, dh):
    return np.stack([slow_of(s, x) for x in variables(other(axis_of(load)))], axis=1)


EFFECT = Effect(
    "lon-lat-coupling",
    "the other axis's states and control drive the loads",
    "averaged",
    _columns,
    crosses_axes=True,
)
