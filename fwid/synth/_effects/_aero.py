"""Forms of `nonlinear-aero` and of `unsteady-aero` (both in the catalogue).

`nonlinear-aero`: extra cycle-averaged loads, nonlinear in the perturbation states; every
form has longitudinal terms (from lon states, on X Z M) and lateral ones (from lat states,
on Y L N), so a flight of either axis shows it. `s` is the strength.

- `quadratic` (default, index 0): `dX = s cx du^2`, `dZ = s cz dw|dw|`, `dM = s cm dw|dw|`,
  `dY = s cy dv|dv|`, `dN = s cn dv|dv|`.
- `cubic` (1), stall-like (the lift slope falls off at large incidence): `dX = s cx du^3`,
  `dZ = s cz dw^3`, `dM = s cm dw^3`, `dY = s cy dv^3`, `dL = s cl dv^3`, `dN = s cn dv^3`.
- `rate-damping` (2), quadratic damping: `dZ = s cz dq|dq|`, `dM = s cm dq|dq|`,
  `dL = s cl dp|dp|`, `dN = s cn dr|dr|`, `dY = s cy dr|dr|`.
- `cross` (3), products of the two states other than the one each load mainly drives (so
  no term changes its own load's damping or stiffness, which keeps the vehicle stable):
  `dX = s cx dw dq`, `dZ = s cz du dq`, `dM = s cm du dw`, `dY = s cy dp dr`,
  `dL = s cl dv dr`, `dN = s cn dv dp`.
- `saturation` (4), loads that level off (the attached-flow load stops growing with the
  speed and incidence): a fraction `W` (`s lon` for u, w; `s lat` for v) of the loads the
  linear model gives those states (their columns of `Fx`) saturates, odd and linear at small
  perturbations: the extra load `Fx W (S tanh(x / S) - x)` for x = du, dw, dv with fixed
  scales `S` (`su`, `sw`, `sv` [m/s]). At large perturbations the derivatives keep
  `1 - W` of their value.
- `one-sided` (5), a stall-like kink: beyond a fixed threshold of one sign of the incidence
  (`w0`, `v0` [m/s]) a fraction `W` of the incidence's load goes missing: the extra load
  `-Fx W max(x - x0, 0)` for x = dw, dv (`s lon`, `s lat`).

`unsteady-aero`: part of the state-dependent
cycle-averaged aerodynamic loads (Eqs. 1-6) follows the states late (a lagging wake). `W`
is the lagging fraction (`s wlon` on the lon states q u w, `s wlat` on p r v: the lateral
one smaller because the fast roll mode makes any lag there much stronger); `xl` the lagged
states (auxiliary states started at the initial state), the extra load `Fx W (xl - xc)`:

- `state-lag` (default, index 0): every state, first order, `xl' = (xc - xl) / tau`,
  `tau` = 0.075 s.
- `incidence-lag` (1): only the incidence states w (lon) and v (lat), first order with
  `tau` = 0.05 s (the Wagner lag of the lift on the angle of attack or sideslip).
- `second-order` (2): every state through two first-order stages of `tau` = 0.04 s each
  (a Kuessner-like response that starts flat).
- `lift-lag` (3): every state, first order, `tau` = 0.075 s (a larger lateral fraction), but only the loads Z, M (lon)
  and Y, N (lat) lag: X and L follow the states at once.
- `wagner` (4): the circulatory load (from the incidence w, v and the rates q, p, r) through a
  two-pole indicial response (Jones' approximation of Wagner's function,
  `1 - A1 exp(-t / tau1) - A2 exp(-t / tau2)`): two parallel first-order lags,
  `x1' = (xc - x1) / tau1`, `x2' = (xc - x2) / tau2`, the extra load
  `Fx W (a1 (x1 - xc) + a2 (x2 - xc))` with `a1 + a2 = 1` (Jones' 0.165 : 0.335) and
  `tau1` = 0.25 s, `tau2` = 0.04 s: a fast lag of most of the deficit and a slow tail.
"""

from __future__ import annotations

import numpy as np

from .._delfly import aero_matrices
from ._form import Form, loads


def _sq(x):
    return x * np.abs(x)


class Quadratic(Form):
    effect, name = "nonlinear-aero", "quadratic"
    COEFFICIENTS = {"cx": -0.15, "cz": -0.25, "cm": 6.0e-3, "cy": -0.08, "cn": -1.5e-3}

    def extra_loads(self, xc, u, aux):
        c = self.c
        du, dw, dv = xc[..., 1], xc[..., 2], xc[..., 6]
        return loads(np.shape(xc)[:-1], X=c["cx"] * du * du, Z=c["cz"] * dw * np.abs(dw),
                     M=c["cm"] * dw * np.abs(dw), Y=c["cy"] * dv * np.abs(dv),
                     N=c["cn"] * dv * np.abs(dv))


class Cubic(Form):
    effect, name = "nonlinear-aero", "cubic"
    COEFFICIENTS = {"cx": -0.84, "cz": -5.9, "cm": -0.27, "cy": -0.27, "cl": -4.1e-5, "cn": -4.5e-3}

    def extra_loads(self, xc, u, aux):
        c = self.c
        du3, dw3, dv3 = xc[..., 1] ** 3, xc[..., 2] ** 3, xc[..., 6] ** 3
        return loads(np.shape(xc)[:-1], X=c["cx"] * du3, Z=c["cz"] * dw3, M=c["cm"] * dw3,
                     Y=c["cy"] * dv3, L=c["cl"] * dv3, N=c["cn"] * dv3)


class RateDamping(Form):
    effect, name = "nonlinear-aero", "rate-damping"
    COEFFICIENTS = {"cz": -0.016, "cm": -7.6e-4, "cl": -2.7e-7, "cn": -7.6e-4, "cy": -4.0e-3}

    def extra_loads(self, xc, u, aux):
        c = self.c
        qq, pp, rr = _sq(xc[..., 0]), _sq(xc[..., 4]), _sq(xc[..., 5])
        return loads(np.shape(xc)[:-1], Z=c["cz"] * qq, M=c["cm"] * qq, L=c["cl"] * pp,
                     N=c["cn"] * rr, Y=c["cy"] * rr)


class Cross(Form):
    effect, name = "nonlinear-aero", "cross"
    COEFFICIENTS = {"cx": -0.025, "cz": -0.08, "cm": 0.022, "cy": -7.6e-3, "cl": 1.2e-5,
                    "cn": -1.8e-4}

    def extra_loads(self, xc, u, aux):
        c = self.c
        dq, du, dw, dp, dr, dv = (xc[..., i] for i in (0, 1, 2, 4, 5, 6))
        return loads(np.shape(xc)[:-1], X=c["cx"] * dw * dq, Z=c["cz"] * du * dq,
                     M=c["cm"] * du * dw, Y=c["cy"] * dp * dr, L=c["cl"] * dv * dr,
                     N=c["cn"] * dv * dp)


class Saturation(Form):
    effect, name = "nonlinear-aero", "saturation"
    COEFFICIENTS = {"lon": 0.4, "lat": 0.15, "su": 0.05, "sw": 0.05, "sv": 0.1}
    #: Coefficients that are scales of the states (not scaled by the strength).
    SCALES = ("su", "sw", "sv")
    #: The states whose loads bend (indices into `STATES`) and their scales.
    BENT = ((1, "su"), (2, "sw"), (6, "sv"))

    @classmethod
    def coefficients(cls, strength):
        return {k: float(v if k in cls.SCALES else v * strength)
                for k, v in cls.COEFFICIENTS.items()}

    def __init__(self, strength, vehicle):
        super().__init__(strength, vehicle)
        Fx = aero_matrices(vehicle)[0]
        self._cols = [i for i, _ in self.BENT]
        self._scales = np.array([self.c[k] for _, k in self.BENT])
        w = np.array([self.c["lon" if i < 3 else "lat"] for i in self._cols])
        self._wFx = Fx[:, self._cols] * w  # the bent states' columns of Fx, weighted

    def bend(self, x):
        """The part of the states' load that goes missing, per bent state."""
        s = self._scales
        return s * np.tanh(x / s) - x

    def extra_loads(self, xc, u, aux):
        return self.bend(xc[..., self._cols]) @ self._wFx.T


class OneSided(Saturation):
    effect, name = "nonlinear-aero", "one-sided"
    COEFFICIENTS = {"lon": 0.5, "lat": 0.12, "w0": 0.01, "v0": 0.02}
    SCALES = ("w0", "v0")
    BENT = ((2, "w0"), (6, "v0"))

    def bend(self, x):
        return -np.maximum(x - self._scales, 0.0)


NONLINEAR = (Quadratic, Cubic, RateDamping, Cross, Saturation, OneSided)


class StateLag(Form):
    effect, name = "unsteady-aero", "state-lag"
    COEFFICIENTS = {"tau": 0.075, "lon": 0.5, "lat": 0.15}
    n_aux = 9
    #: The states that lag (indices into `STATES`), and the loads that do (`XYZLMN`).
    LAGGING = (0, 1, 2, 4, 5, 6)
    LOADS = "XYZLMN"
    STAGES = 1

    @classmethod
    def coefficients(cls, strength):
        c = cls.COEFFICIENTS
        return {"tau": c["tau"], "lon": c["lon"] * strength, "lat": c["lat"] * strength}

    def __init__(self, strength, vehicle):
        super().__init__(strength, vehicle)
        self.n_aux = 9 * self.STAGES
        w = np.zeros(9)
        lon = [i for i in self.LAGGING if i < 3]
        lat = [i for i in self.LAGGING if i >= 4]
        w[lon], w[lat] = self.c["lon"], self.c["lat"]
        rows = np.array(["XYZLMN".index(k) for k in self.LOADS])
        wFx = np.zeros((6, 9))
        wFx[rows] = (aero_matrices(vehicle)[0] * w)[rows]
        self._wFx = wFx  # columns of Fx weighted by the fractions, on the lagging loads

    def aux0(self, xc0):
        return np.tile(np.array(xc0, dtype=float), self.STAGES)

    def aux_rhs(self, xc, u_cmd, u, aux):
        tau = self.c["tau"]
        stages = [xc] + [aux[..., 9 * k: 9 * (k + 1)] for k in range(self.STAGES)]
        d = [(stages[k] - stages[k + 1]) / tau for k in range(self.STAGES)]
        return d[0] if self.STAGES == 1 else np.concatenate(d, axis=-1)

    def extra_loads(self, xc, u, aux):
        return (aux[..., -9:] - xc) @ self._wFx.T


class IncidenceLag(StateLag):
    name = "incidence-lag"
    COEFFICIENTS = {"tau": 0.05, "lon": 1.6, "lat": 0.3}
    LAGGING = (2, 6)


class SecondOrder(StateLag):
    name = "second-order"
    COEFFICIENTS = {"tau": 0.04, "lon": 0.4, "lat": 0.1}
    STAGES = 2


class LiftLag(StateLag):
    name = "lift-lag"
    COEFFICIENTS = {"tau": 0.075, "lon": 0.5, "lat": 0.6}
    LOADS = "YZMN"


class Wagner(StateLag):
    name = "wagner"
    COEFFICIENTS = {"tau1": 0.25, "tau2": 0.04, "a1": 0.33, "lon": 0.5, "lat": 0.1}
    LAGGING = (0, 2, 4, 5, 6)

    @classmethod
    def coefficients(cls, strength):
        c = cls.COEFFICIENTS
        return {"tau1": c["tau1"], "tau2": c["tau2"], "a1": c["a1"], "lon": c["lon"] * strength,
                "lat": c["lat"] * strength}

    def __init__(self, strength, vehicle):
        super().__init__(strength, vehicle)
        self.n_aux = 18

    def aux0(self, xc0):
        return np.tile(np.array(xc0, dtype=float), 2)

    def aux_rhs(self, xc, u_cmd, u, aux):
        return np.concatenate([(xc - aux[..., :9]) / self.c["tau1"],
                               (xc - aux[..., 9:]) / self.c["tau2"]], axis=-1)

    def extra_loads(self, xc, u, aux):
        a1 = self.c["a1"]
        lagged = a1 * aux[..., :9] + (1.0 - a1) * aux[..., 9:]
        return (lagged - xc) @ self._wFx.T


UNSTEADY = (StateLag, IncidenceLag, SecondOrder, LiftLag, Wagner)
