"""Forms of `flap-frequency`: the cycle-averaged loads
follow the slow variation of the flapping frequency `f` (which the paper's model uses only
for the phase of Eq. 12). The flights' true frequency wanders by about 0.1 Hz about its
nominal `f0` (`_simulate.FlapFrequency`); `df = f - f0`, `s` is the strength:

- `thrust` (default, index 0): `dX = s cx df`, `dZ = s cz df`, `dM = s cm df` (thrust and
  lift grow with the flapping frequency, with a pitching moment from the thrust line).
- `quadratic` (1): the same loads in `f^2 - f0^2` (thrust proportional to `f^2`).
- `lateral` (2): `dY = s cy df`, `dL = s cl df`, `dN = s cn df` (the two wing pairs
  respond unequally to the frequency).
- `lagged` (3): the `thrust` loads follow `df` through a first-order lag of `tau` = 0.15 s
  (the wake and the wing's flexibility take time to build up).
- `saturating` (4): the `thrust` loads level off with the frequency (the wings' flexibility
  caps the stroke's gain): `df` replaced by `fs tanh(df / fs)`, `fs` = 0.05 Hz fixed.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter, lfilter_zi

from ._form import Form, loads


class Thrust(Form):
    effect, name = "flap-frequency", "thrust"
    COEFFICIENTS = {"cx": 0.015, "cz": -0.024, "cm": 4.5e-4}
    axes = ("lon",)

    def _df(self, t, f):
        return np.asarray(f, dtype=float) - self.vehicle.f0

    def timed_loads(self, t, f):
        c, df = self.c, self._df(t, f)
        return loads(np.shape(df), X=c["cx"] * df, Z=c["cz"] * df, M=c["cm"] * df)


class Quadratic(Thrust):
    name = "quadratic"
    COEFFICIENTS = {"cx": 6.0e-4, "cz": -1.0e-3, "cm": 1.8e-5}

    def _df(self, t, f):
        return np.asarray(f, dtype=float) ** 2 - self.vehicle.f0 ** 2


class Lateral(Form):
    effect, name = "flap-frequency", "lateral"
    COEFFICIENTS = {"cy": 1.35e-3, "cl": 9.0e-6, "cn": 2.25e-5}
    axes = ("lat",)

    def timed_loads(self, t, f):
        c, df = self.c, np.asarray(f, dtype=float) - self.vehicle.f0
        return loads(np.shape(df), Y=c["cy"] * df, L=c["cl"] * df, N=c["cn"] * df)


class Lagged(Thrust):
    name = "lagged"
    COEFFICIENTS = {"cx": 0.018, "cz": -0.03, "cm": 6.0e-4}
    TAU = 0.15

    def _df(self, t, f):
        t, x = np.asarray(t, dtype=float), np.asarray(f, dtype=float) - self.vehicle.f0
        if len(t) < 2:
            return x
        a = np.exp(-(t[1] - t[0]) / self.TAU)  # the grids given are uniform
        b = (0.5 * (1.0 - a), 0.5 * (1.0 - a))
        y, _ = lfilter(b, (1.0, -a), x, zi=lfilter_zi(b, (1.0, -a)) * x[0])
        return y


class Saturating(Thrust):
    name = "saturating"
    COEFFICIENTS = {"cx": 0.0255, "cz": -0.041, "cm": 7.7e-4}
    SCALE = 0.05

    def _df(self, t, f):
        df = np.asarray(f, dtype=float) - self.vehicle.f0
        return self.SCALE * np.tanh(df / self.SCALE)


FORMS = (Thrust, Quadratic, Lateral, Lagged, Saturating)
