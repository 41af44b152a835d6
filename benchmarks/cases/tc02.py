"""FVSysID test case 2: lateral-directional motion in turbulence (simulated, process noise).

R. V. Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, chapter 5
(filter-error method), test case 2; the model restated from the book's model definition
(``mDefCase02``, state equation (5.83), observation equation (5.84)):

    states x = [p, r]; inputs u = [da, dr, v] (v, the lateral velocity, used as an input)
    p' = Lp p + Lr r + Lda da + Ldr dr + Lv v + BX1
    r' = Np p + Nr r + Nda da + Ndr dr + Nv v + BX2
    outputs [pdot, rdot, ay, p, r]:
        pdot = Lp p + Lr r + Lda da + Ldr dr + Lv v + BY1   (BX1 lumped into BY1)
        rdot = Np p + Nr r + Nda da + Ndr dr + Nv v + BY2
        ay   = Yp p + Yr r + Yda da + Ydr dr + Yv v + BY3
        p + BY4,  r + BY5

TC01's parameter names with ``v`` for beta. Data: ``y13aus_da1.asc`` (simulated with
turbulence; outputs columns 12-16, inputs 17-19, 1-based), on the time axis ``0.05 k``,
x0 = 0 (fixed). Start values: the book's, process noise F = (0.02, 0.02).
"""

from __future__ import annotations

import numpy as np

from .textbook import Case, data_root

NAMES = ("Lp", "Lr", "Lda", "Ldr", "Lv", "Np", "Nr", "Nda", "Ndr", "Nv",
         "Yp", "Yr", "Yda", "Ydr", "Yv", "BX1", "BX2", "BY1", "BY2", "BY3", "BY4", "BY5")
THETA0 = np.array([-6.7, 1.83, -18.3, 0.43, -0.114, -0.906, -0.665, -0.66, -2.82, 0.0069,
                   -0.64, 1.30, -1.40, 2.79, -0.193, 0.08, -0.089,
                   0.08, -0.089, 0.044, -0.0034, -0.0015])
F0 = np.array([0.02, 0.02])
FILE = "jategaonkar_fvsysid2/y13aus_da1.asc"
DT = 0.05


def _lin(x, u, p, a):
    return (p[a + "p"] * x[..., 0] + p[a + "r"] * x[..., 1] + p[a + "da"] * u[..., 0]
            + p[a + "dr"] * u[..., 1] + p[a + "v"] * u[..., 2])


def xdot(x, u, p, c, xp):
    """Eq. (5.83)."""
    return xp.stack([_lin(x, u, p, "L") + p["BX1"], _lin(x, u, p, "N") + p["BX2"]], axis=-1)


def obs(x, u, p, c, xp):
    """Eq. (5.84)."""
    return xp.stack([_lin(x, u, p, "L") + p["BY1"], _lin(x, u, p, "N") + p["BY2"],
                     _lin(x, u, p, "Y") + p["BY3"], x[..., 0] + p["BY4"],
                     x[..., 1] + p["BY5"]], axis=-1)


def records() -> list[dict]:
    a = np.loadtxt(data_root() / FILE)
    col = lambda k: a[:, k - 1]  # noqa: E731  (1-based, as PROVENANCE.md)
    z = np.column_stack([col(12), col(13), col(14), col(15), col(16)])
    u = np.column_stack([col(17), col(18), col(19)])
    t = DT * np.arange(len(a))
    return [{"name": "y13aus_da1", "t": t, "u": u, "z": z, "x0": np.zeros(2), "consts": {}}]


CASE = Case(
    key="tc02_fem", title="FVSysID TC02: lateral-directional in turbulence, 5 outputs",
    names=NAMES, theta0=THETA0, states=("p", "r"), inputs=("da", "dr", "v"),
    outputs=("pdot", "rdot", "ay", "p", "r"), xdot=xdot, obs=obs, records=records,
    files=(FILE,),
)
