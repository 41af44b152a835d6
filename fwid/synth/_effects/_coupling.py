"""Forms of `lon-lat-coupling`: loads of one axis driven by the other's states or inputs.
`s` is the strength; all terms linear, on cycle-averaged perturbations.

- `control` (default, index 0): the elevator and pitch rate drive the lateral loads and the
  rudder the pitching moment, `dY = s ye dde`, `dL = s (le dde + lq dq)`,
  `dN = s (ne dde + nq dq)`, `dM = s md ddr`. Both manoeuvres show it.
- `lat-to-lon` (1): lateral states drive longitudinal loads only, `dX = s xv dv`,
  `dZ = s (zv dv + zp dp)`, `dM = s (mp dp + mr dr + mv dv)`. Only a lateral manoeuvre
  shows it (on X Z M; Y L N untouched).
- `lon-to-lat` (2): longitudinal velocities drive lateral loads only,
  `dY = s (yu du + yw dw)`, `dL = s lw dw`, `dN = s (nu du + nw dw)`. Only a longitudinal
  manoeuvre shows it (on Y L N; X Z M untouched).
- `rates` (3): the pitch rate drives the lateral loads (a gyroscopic-like coupling of the
  flapping wings), `dY = s yq dq`, `dL = s lq dq`, `dN = s nq dq`. Only a longitudinal
  manoeuvre shows it. (Rates coupling both ways closes a loop through the fast roll mode
  that diverges at strength 2, so it is one-way.)
- `gyroscopic` (4): a spinning rotor (the motor and gearbox) with its angular momentum along
  the body x axis (its sign the rotor's direction): the body rates turn it, and its reaction
  is a moment across them, `dM = s hm dr`, `dN = -s hn dq` (an ideal rotor has `hm = hn`,
  which does no work; each is sized here to the noise on its own load, like every form).
  Both manoeuvres show it (a pitching manoeuvre on N, a lateral one on M).
"""

from __future__ import annotations

import numpy as np

from ._form import Form, loads


class Control(Form):
    effect, name = "lon-lat-coupling", "control"
    COEFFICIENTS = {"ye": -0.02, "le": 2.0e-5, "lq": 1.0e-6, "ne": -5.0e-4, "nq": 2.0e-5,
                    "md": 2.0e-3}

    def extra_loads(self, xc, u, aux):
        c = self.c
        de, dr, dq = u[..., 0], u[..., 1], xc[..., 0]
        return loads(np.shape(xc)[:-1], Y=c["ye"] * de, L=c["le"] * de + c["lq"] * dq,
                     N=c["ne"] * de + c["nq"] * dq, M=c["md"] * dr)


class LatToLon(Form):
    effect, name = "lon-lat-coupling", "lat-to-lon"
    COEFFICIENTS = {"xv": 5.8e-3, "zv": -0.019, "zp": -3.8e-4, "mp": 9.1e-6, "mr": 4.6e-5,
                    "mv": 9.1e-4}
    axes = ("lat",)

    def extra_loads(self, xc, u, aux):
        c = self.c
        dp, dr, dv = xc[..., 4], xc[..., 5], xc[..., 6]
        return loads(np.shape(xc)[:-1], X=c["xv"] * dv, Z=c["zv"] * dv + c["zp"] * dp,
                     M=c["mp"] * dp + c["mr"] * dr + c["mv"] * dv)


class LonToLat(Form):
    effect, name = "lon-lat-coupling", "lon-to-lat"
    COEFFICIENTS = {"yu": 0.066, "yw": -0.066, "lw": 8.3e-6, "nu": 1.1e-3, "nw": -1.1e-3}
    axes = ("lon",)

    def extra_loads(self, xc, u, aux):
        c = self.c
        du, dw = xc[..., 1], xc[..., 2]
        return loads(np.shape(xc)[:-1], Y=c["yu"] * du + c["yw"] * dw, L=c["lw"] * dw,
                     N=c["nu"] * du + c["nw"] * dw)


class Rates(Form):
    effect, name = "lon-lat-coupling", "rates"
    COEFFICIENTS = {"yq": -8.3e-3, "lq": 1.3e-6, "nq": 1.4e-4}
    axes = ("lon",)

    def extra_loads(self, xc, u, aux):
        c = self.c
        dq = xc[..., 0]
        return loads(np.shape(xc)[:-1], Y=c["yq"] * dq, L=c["lq"] * dq, N=c["nq"] * dq)


class Gyroscopic(Form):
    effect, name = "lon-lat-coupling", "gyroscopic"
    COEFFICIENTS = {"hm": 6.0e-4, "hn": 1.5e-4}

    def extra_loads(self, xc, u, aux):
        c = self.c
        return loads(np.shape(xc)[:-1], M=c["hm"] * xc[..., 5], N=-c["hn"] * xc[..., 0])


FORMS = (Control, LatToLon, LonToLat, Rates, Gyroscopic)
