"""FVSysID test case 2: lateral-directional motion simulated with turbulence (process noise).

R. V. Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, chapter 5
(filter error method; the book's ``mDefCase02``), restated as its output-error part (no
process-noise matrix F):

    states x = [p, r]; inputs u = [da, dr, v] (v: lateral velocity as a pseudo-input)
    p' = Lp p + Lr r + Lda da + Ldr dr + Lv v + bxp
    r' = Np p + Nr r + Nda da + Ndr dr + Nv v + bxr
    outputs [pdot, rdot, ay, p, r]:
      pdot = (p' without bxp) + byp_dot,  rdot = (r' without bxr) + byr_dot,
      ay = Yp p + Yr r + Yda da + Ydr dr + Yv v + byay,  p + byp,  r + byr

Data: ``y13aus_da1.asc`` (321 samples, 0.05 s; outputs columns 12-16, inputs 17-19), x0 = 0.
Start values: the book's. The record was simulated with turbulence, so the residuals of any
output-error fit are process noise, coloured and correlated between the outputs: the book
fits it with the filter error method.
"""

from __future__ import annotations

import numpy as np

from _textbook import Case, data_root

NAMES = ("Lp", "Lr", "Np", "Nr", "Lda", "Ldr", "Lv", "Nda", "Ndr", "Nv",
         "Yp", "Yr", "Yda", "Ydr", "Yv", "bxp", "bxr", "bypd", "byrd", "byay", "byp", "byr")
THETA0 = np.array([-6.7, 1.83, -0.906, -0.665, -18.3, 0.43, -0.114, -0.66, -2.82, 0.0069,
                   -0.64, 1.30, -1.40, 2.79, -0.193, 0.08, -0.089,
                   0.08, -0.089, 0.044, -0.0034, -0.0015])
FILE = "jategaonkar_fvsysid2/y13aus_da1.asc"


def _rates(x, u, p, xp):
    P, R = x[..., 0], x[..., 1]
    da, dr, v = u[..., 0], u[..., 1], u[..., 2]
    pd = p["Lp"] * P + p["Lr"] * R + p["Lda"] * da + p["Ldr"] * dr + p["Lv"] * v
    rd = p["Np"] * P + p["Nr"] * R + p["Nda"] * da + p["Ndr"] * dr + p["Nv"] * v
    ay = p["Yp"] * P + p["Yr"] * R + p["Yda"] * da + p["Ydr"] * dr + p["Yv"] * v
    return pd, rd, ay


def xdot(x, u, p, c, xp):
    pd, rd, _ = _rates(x, u, p, xp)
    return xp.stack([pd + p["bxp"], rd + p["bxr"]], axis=-1)


def obs(x, u, p, c, xp):
    pd, rd, ay = _rates(x, u, p, xp)
    return xp.stack([pd + p["bypd"], rd + p["byrd"], ay + p["byay"], x[..., 0] + p["byp"],
                     x[..., 1] + p["byr"]], axis=-1)


def records() -> list[dict]:
    a = np.loadtxt(data_root() / FILE)
    t = 0.05 * np.arange(len(a))
    return [{"name": "y13aus_da1", "t": t, "u": a[:, 16:19], "z": a[:, 11:16],
             "x0": np.zeros(2), "consts": {}}]


CASE = Case(
    key="tc02_turbulence", title="FVSysID TC02: lateral, simulated with turbulence, 5 outputs",
    names=NAMES, theta0=THETA0, states=("p", "r"), inputs=("da", "dr", "v"),
    outputs=("pdot", "rdot", "ay", "p", "r"), xdot=xdot, obs=obs, records=records,
    files=(FILE,),
)
