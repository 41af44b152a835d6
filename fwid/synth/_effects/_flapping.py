"""Forms of `flap-coupling`: the flapping loads (Eq. 12) follow the body motion or the
inputs, breaking time-scale separation. `s` is the strength; states are the cycle-averaged
perturbations; `F = sum_n H_n` the flapping loads of Eq. 12, `H_n = a_n sin(n phi) +
b_n cos(n phi)`, `Q_n = a_n cos(n phi) - b_n sin(n phi)` (n = 1..3).

- `amplitude` (default, index 0): every harmonic of every load scaled by the states,
  `F' = F (1 + s (kw dw + kq dq + kv dv + kp dp))`.
- `control` (1): scaled by the control deflections, `F' = F (1 + s (ke dde + kr ddr))`.
- `phase` (2): the flapping phase shifted by the states, `F' = sum_n H_n cos(n d) + Q_n
  sin(n d)` = Eq. 12 at `phi + d`, `d = s (cw dw + cq dq + cv dv + cp dp)` [rad].
- `shape` (3): only the 2nd and 3rd harmonics scaled (the wave shape changes, the
  fundamental does not), `F' = F + s (k2u du + k2v dv) H_2 + s (k3w dw + k3r dr) H_3`.
"""

from __future__ import annotations

import numpy as np

from ._form import Form


class Amplitude(Form):
    effect, name = "flap-coupling", "amplitude"
    COEFFICIENTS = {"kw": 1.5, "kq": 0.1, "kv": 1.0, "kp": 0.02}
    harmonics = False

    def flapping(self, xc, u, F, H, Q):
        c = self.c
        dq, dp, dw, dv = xc[..., 0], xc[..., 4], xc[..., 2], xc[..., 6]
        gain = 1.0 + c["kw"] * dw + c["kq"] * dq + c["kv"] * dv + c["kp"] * dp
        return F * np.asarray(gain)[..., None]


class Control(Form):
    effect, name = "flap-coupling", "control"
    COEFFICIENTS = {"ke": 2.3, "kr": 1.1}

    def flapping(self, xc, u, F, H, Q):
        gain = 1.0 + self.c["ke"] * u[..., 0] + self.c["kr"] * u[..., 1]
        return F * np.asarray(gain)[..., None]


_N = np.arange(1.0, 4.0)


class Phase(Form):
    effect, name = "flap-coupling", "phase"
    COEFFICIENTS = {"cw": 0.84, "cq": 0.084, "cv": 0.56, "cp": 0.011}
    harmonics = True

    def flapping(self, xc, u, F, H, Q):
        c = self.c
        d = c["cw"] * xc[..., 2] + c["cq"] * xc[..., 0] + c["cv"] * xc[..., 6] + c["cp"] * xc[..., 4]
        nd = np.asarray(d)[..., None] * _N  # (..., 3)
        return F + np.einsum("...n,...nk->...k", np.cos(nd) - 1.0, H) + np.einsum(
            "...n,...nk->...k", np.sin(nd), Q)


class Shape(Form):
    effect, name = "flap-coupling", "shape"
    COEFFICIENTS = {"k2u": 3.2, "k3w": 3.2, "k2v": 1.4, "k3r": 0.14}
    harmonics = True

    def flapping(self, xc, u, F, H, Q):
        c = self.c
        g2 = c["k2u"] * xc[..., 1] + c["k2v"] * xc[..., 6]
        g3 = c["k3w"] * xc[..., 2] + c["k3r"] * xc[..., 5]
        return F + np.asarray(g2)[..., None] * H[..., 1, :] + np.asarray(g3)[..., None] * H[..., 2, :]


FORMS = (Amplitude, Control, Phase, Shape)
