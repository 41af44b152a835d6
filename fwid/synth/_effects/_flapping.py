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
- `harmonic` (4): one harmonic alone, the 2nd, modulated in amplitude by the incidence and
  the rates (the stroke's up/down asymmetry changes with them; the fundamental and the 3rd
  do not), `F' = F + s (hw dw + hq dq + hv dv + hp dp) H_2`.
"""

from __future__ import annotations

import numpy as np

from ._form import Form


_STATE = {"q": 0, "u": 1, "w": 2, "p": 4, "r": 5, "v": 6}


def _sum(c, xc, keys, start=0.0):
    """`start + sum_k c[k] x_k` (left to right; coefficient `k` names its state last:
    `kw` -> w, `k2u` -> u)."""
    out = start
    for k in keys:
        out = out + c[k] * xc[..., _STATE[k[-1]]]
    return np.asarray(out)


class _Gain(Form):
    """Every harmonic scaled by one gain, `F' = F gain(xc, u)`."""

    def gain(self, xc, u):
        raise NotImplementedError

    def flapping(self, xc, u, F, H, Q):
        return F * np.asarray(self.gain(xc, u))[..., None]


class Amplitude(_Gain):
    effect, name = "flap-coupling", "amplitude"
    COEFFICIENTS = {"kw": 1.5, "kq": 0.1, "kv": 1.0, "kp": 0.02}

    def gain(self, xc, u):
        return _sum(self.c, xc, ("kw", "kq", "kv", "kp"), 1.0)


class Control(_Gain):
    effect, name = "flap-coupling", "control"
    COEFFICIENTS = {"ke": 2.3, "kr": 1.1}

    def gain(self, xc, u):
        return 1.0 + self.c["ke"] * u[..., 0] + self.c["kr"] * u[..., 1]


_N = np.arange(1.0, 4.0)


class Phase(Form):
    effect, name = "flap-coupling", "phase"
    COEFFICIENTS = {"cw": 0.84, "cq": 0.084, "cv": 0.56, "cp": 0.011}
    harmonics = True

    def flapping(self, xc, u, F, H, Q):
        nd = _sum(self.c, xc, ("cw", "cq", "cv", "cp"))[..., None] * _N  # (..., 3)
        return F + np.einsum("...n,...nk->...k", np.cos(nd) - 1.0, H) + np.einsum(
            "...n,...nk->...k", np.sin(nd), Q)


class Shape(Form):
    effect, name = "flap-coupling", "shape"
    COEFFICIENTS = {"k2u": 3.2, "k3w": 3.2, "k2v": 1.4, "k3r": 0.14}
    harmonics = True

    def flapping(self, xc, u, F, H, Q):
        g2, g3 = _sum(self.c, xc, ("k2u", "k2v")), _sum(self.c, xc, ("k3w", "k3r"))
        return F + g2[..., None] * H[..., 1, :] + g3[..., None] * H[..., 2, :]


class Harmonic(Form):
    effect, name = "flap-coupling", "harmonic"
    COEFFICIENTS = {"hw": 2.4, "hq": 0.16, "hv": 1.6, "hp": 0.032}
    harmonics = True

    def flapping(self, xc, u, F, H, Q):
        g = _sum(self.c, xc, ("hw", "hq", "hv", "hp"))
        return F + g[..., None] * H[..., 1, :]


FORMS = (Amplitude, Control, Phase, Shape, Harmonic)
