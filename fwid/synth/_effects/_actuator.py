"""Forms of `actuator-dynamics` (in the catalogue) and `sensor-offset` (outside it).

`actuator-dynamics`: the deflection acting on the vehicle, `u_eff`, is the commanded one
through some dynamics; the measured columns `de`, `dr` keep the commanded deflection. So the
response LAGS the measured input. The strength `s` scales the time scales (so `s = 0`, no
dynamics, is exactly the flight without the effect):

- `lag` (default, index 0): first order, `u_eff' = (u_cmd - u_eff) / tau`, `tau = s tau1`.
- `delay` (1): pure time delay, `u_eff(t) = u_cmd(t - T)`, `T = s T1` (the commanded
  deflection is linear between samples, so the delayed one is exact at any `T`).
- `servo` (2): second order, `u_eff'' = wn^2 (u_cmd - u_eff) - 2 zeta wn u_eff'`,
  `wn = 2 pi fn / s` (fn at strength 1), `zeta` fixed.
- `rate-limit` (3): first-order lag whose rate saturates, `u_eff' = clip((u_cmd - u_eff) /
  tau, -rmax, rmax)`, `tau = s tau1`, `rmax = rmax1 / s` [rad/s].

`sensor-offset` (`trailing`, outside the catalogue): the true deflection acts at once, but
the logged control columns `de`, `dr` trail it by `T = s T1` seconds (the whole measured
column, ripple included, is `col(t - T)`; before `T` it holds its first value). So the
response seems to LEAD the measured input: the opposite sign of an actuator delay, which no
causal actuator model can produce.
"""

from __future__ import annotations

import numpy as np

from ._form import Form


def _delayed(tq, t, x, T):
    """`x` (samples at `t`, linear between them; first value before `t[0]`) at `tq - T`."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        return np.interp(np.asarray(tq) - T, t, x)
    return np.stack([np.interp(np.asarray(tq) - T, t, x[:, i]) for i in range(x.shape[1])], axis=1)


class Lag(Form):
    effect, name = "actuator-dynamics", "lag"
    COEFFICIENTS = {"tau": 0.05}
    n_aux = 2

    def actuator(self, u, aux):
        return aux

    def aux_rhs(self, xc, u_cmd, u, aux):
        return (u_cmd - u) / self.c["tau"]


class Delay(Form):
    effect, name = "actuator-dynamics", "delay"
    COEFFICIENTS = {"delay": 0.04}

    def command(self, tq, t, u_cmd):
        return _delayed(tq, t, u_cmd, self.c["delay"])


class Servo(Form):
    effect, name = "actuator-dynamics", "servo"
    COEFFICIENTS = {"fn": 8.0, "zeta": 0.6}
    n_aux = 4

    @classmethod
    def coefficients(cls, strength):
        return {"fn": cls.COEFFICIENTS["fn"] / strength if strength else float("inf"),
                "zeta": cls.COEFFICIENTS["zeta"]}

    def actuator(self, u, aux):
        return aux[..., :2]

    def aux_rhs(self, xc, u_cmd, u, aux):
        wn = 2 * np.pi * self.c["fn"]
        acc = wn * wn * (u_cmd - aux[..., :2]) - 2 * self.c["zeta"] * wn * aux[..., 2:]
        return np.concatenate([aux[..., 2:], acc], axis=-1)


class RateLimit(Lag):
    effect, name = "actuator-dynamics", "rate-limit"
    COEFFICIENTS = {"tau": 0.03, "rmax": 3.0}

    @classmethod
    def coefficients(cls, strength):
        return {"tau": cls.COEFFICIENTS["tau"] * strength,
                "rmax": cls.COEFFICIENTS["rmax"] / strength if strength else float("inf")}

    def aux_rhs(self, xc, u_cmd, u, aux):
        r = self.c["rmax"]
        return np.clip((u_cmd - u) / self.c["tau"], -r, r)


ACTUATOR = (Lag, Delay, Servo, RateLimit)


class Trailing(Form):
    effect, name = "sensor-offset", "trailing"
    COEFFICIENTS = {"offset": 0.04}

    def measured(self, t, column):
        return _delayed(t, t, column, self.c["offset"])


SENSOR = (Trailing,)
