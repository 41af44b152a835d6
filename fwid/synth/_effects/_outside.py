"""Deterministic effects outside the catalogue (besides the gusts of `_gusts.py`): structure
that `fwid.diagnose` should call `unexplained`, never a catalogue name. `s` is the strength.

- `cg-offset` (`attitude`): the loads follow the attitude angle, as a centre of gravity away
  from the reference point makes the weight's moment change with it: `dX = s cx dtheta`,
  `dM = s cm dtheta` (lon), `dY = s cy dphi`, `dL = s cl dphi` (lat).
- `battery-sag` (`linear`): thrust and lift fall over the flight as the battery drains, the
  same in every flight: `dX = -s cx t`, `dZ = s cz t`, `dM = -s cm t` (lon).
"""

from __future__ import annotations

import numpy as np

from ._form import Form, loads


class Attitude(Form):
    effect, name = "cg-offset", "attitude"
    COEFFICIENTS = {"cx": -0.03, "cm": -3.6e-3, "cy": 1.05e-3, "cl": -7.0e-6}

    def extra_loads(self, xc, u, aux):
        c = self.c
        th, ph = xc[..., 3], xc[..., 7]
        return loads(np.shape(xc)[:-1], X=c["cx"] * th, M=c["cm"] * th, Y=c["cy"] * ph,
                     L=c["cl"] * ph)


class Linear(Form):
    effect, name = "battery-sag", "linear"
    COEFFICIENTS = {"cx": 7.0e-4, "cz": 1.05e-3, "cm": 2.1e-5}
    axes = ("lon",)

    def timed_loads(self, t, f):
        c, t = self.c, np.asarray(t, dtype=float)
        return loads(np.shape(t), X=-c["cx"] * t, Z=c["cz"] * t, M=-c["cm"] * t)


CG_OFFSET = (Attitude,)
BATTERY_SAG = (Linear,)
