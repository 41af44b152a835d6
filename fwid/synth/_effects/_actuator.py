"""Forms of `actuator-dynamics` and `time-offset` (both in the catalogue).

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
- `asymmetric` (4): a first-order lag whose time constant depends on the direction of travel
  (a servo that is slower against the airload): `tau_up` while `u_cmd > u_eff`, `tau_down`
  otherwise, both `s` times their value at strength 1.
- `lag-delay` (5): a transport delay `T = s T1` followed by a first-order lag `tau = s tau1`.
- `saturation` (6), Hammerstein: the commanded deflection through a soft travel limit, then
  a first-order lag: `u_sat = m tanh(u_cmd / m)`, `u_eff' = (u_sat - u_eff) / tau`,
  `m = m1 / s` per surface (`limit_de`, `limit_dr` [rad], a fraction of the default
  manoeuvre's amplitude at strength 1), `tau = s tau1`.
- `backlash` (7): play in the linkage, then a lag: the deflection moves only while the
  command pulls it beyond a dead band of half-width `b`, `u_eff' = dz(u_cmd - u_eff) / tau`,
  `dz(e) = sign(e) max(|e| - b, 0)` (it holds on a reversal until the command has crossed the
  band: hysteresis), `b = s b1` per surface (`play_de`, `play_dr` [rad]), `tau = s tau1`.

`time-offset` (`sensor-offset` is an alias): the true
deflection acts at once, but the logged control columns `de`, `dr` (the whole measured
column, ripple included) are late against the states. So the response seems to LEAD the
measured input: the opposite sign of an actuator delay, which no causal actuator model can
produce (an offset of the other sign is indistinguishable from a pure actuator delay and is
named `actuator-dynamics`). Before the offset the column holds its first value.

- `trailing` (default, index 0): a constant offset, `col(t - T)`, `T = s T1`.
- `clock-drift` (1): the two clocks run at different rates, so the offset grows over the
  flight from zero: `col(t - k t)`, `k = s k1` [s per s].
- `sample-hold` (2): the controls are logged by a slower loop that holds each value for
  `Th = s Th1` seconds on a grid half a period after the flight's clock (`col(Th
  (floor(t / Th - 1/2) + 1/2))`): late by `Th / 2` on average, in steps.
- `wandering` (3): a clock synchronisation that hunts: the offset wanders slowly about
  `T = s T1`, `col(t - T (1 + 0.5 sin(2 pi 0.3 t)))`.
- `resync` (4): the clocks drift apart and are resynchronised every `P` = 1.5 s: the offset
  grows at `k = s k1` [s per s] from zero and snaps back to zero at each resynchronisation, a
  sawtooth between 0 and `k P` (at the start two thirds of the way up: the first
  resynchronisation is `P / 3` into the flight).
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


class Asymmetric(Lag):
    effect, name = "actuator-dynamics", "asymmetric"
    COEFFICIENTS = {"tau_up": 0.02, "tau_down": 0.08}

    def aux_rhs(self, xc, u_cmd, u, aux):
        up = u_cmd > u
        return (u_cmd - u) / np.where(up, self.c["tau_up"], self.c["tau_down"])


class LagDelay(Lag):
    effect, name = "actuator-dynamics", "lag-delay"
    COEFFICIENTS = {"tau": 0.04, "delay": 0.03}

    def command(self, tq, t, u_cmd):
        return _delayed(tq, t, u_cmd, self.c["delay"])


class Saturation(Lag):
    effect, name = "actuator-dynamics", "saturation"
    COEFFICIENTS = {"tau": 0.03, "limit_de": 0.08, "limit_dr": 0.17}

    @classmethod
    def coefficients(cls, strength):
        c = cls.COEFFICIENTS
        inf = float("inf")
        return {"tau": c["tau"] * strength,
                "limit_de": c["limit_de"] / strength if strength else inf,
                "limit_dr": c["limit_dr"] / strength if strength else inf}

    def aux_rhs(self, xc, u_cmd, u, aux):
        m = np.array([self.c["limit_de"], self.c["limit_dr"]])
        return (m * np.tanh(u_cmd / m) - u) / self.c["tau"]


class Backlash(Lag):
    effect, name = "actuator-dynamics", "backlash"
    COEFFICIENTS = {"tau": 0.03, "play_de": 0.01, "play_dr": 0.02}

    def aux_rhs(self, xc, u_cmd, u, aux):
        b = np.array([self.c["play_de"], self.c["play_dr"]])
        e = u_cmd - u
        return np.sign(e) * np.maximum(np.abs(e) - b, 0.0) / self.c["tau"]


ACTUATOR = (Lag, Delay, Servo, RateLimit, Asymmetric, LagDelay, Saturation, Backlash)


class Trailing(Form):
    effect, name = "time-offset", "trailing"
    COEFFICIENTS = {"offset": 0.04}

    def measured(self, t, column):
        return _delayed(t, t, column, self.c["offset"])


class ClockDrift(Form):
    effect, name = "time-offset", "clock-drift"
    COEFFICIENTS = {"drift": 0.02}

    def measured(self, t, column):
        t = np.asarray(t, dtype=float)
        return _delayed(t, t, column, self.c["drift"] * (t - t[0]))


class SampleHold(Form):
    effect, name = "time-offset", "sample-hold"
    COEFFICIENTS = {"hold": 0.05}

    def measured(self, t, column):
        t = np.asarray(t, dtype=float)
        th = self.c["hold"]  # the logger's grid starts half a period after the flight's
        held = t[0] + th * (np.floor((t - t[0]) / th - 0.5) + 0.5)
        return _delayed(held, t, column, 0.0)


class Wandering(Form):
    effect, name = "time-offset", "wandering"
    COEFFICIENTS = {"offset": 0.04}

    def measured(self, t, column):
        t = np.asarray(t, dtype=float)
        T = self.c["offset"] * (1.0 + 0.5 * np.sin(2 * np.pi * 0.3 * (t - t[0])))
        return _delayed(t, t, column, T)


class Resync(Form):
    effect, name = "time-offset", "resync"
    COEFFICIENTS = {"drift": 0.035}
    PERIOD = 1.5

    def measured(self, t, column):
        t = np.asarray(t, dtype=float)
        since = np.mod(t - t[0] + 2.0 * self.PERIOD / 3.0, self.PERIOD)
        return _delayed(t, t, column, self.c["drift"] * since)


SENSOR = (Trailing, ClockDrift, SampleHold, Wandering, Resync)
