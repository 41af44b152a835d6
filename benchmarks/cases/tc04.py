"""FVSysID test case 4: HFB-320 longitudinal motion, nonlinear model, 4 states, 7 outputs.

R. V. Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, chapter 4,
test case 4; state equations (5.86)-(5.87), observation equations (5.87)-(5.89), restated
from the book's model definition (``mDefCase04``):

    states x = [V, alpha, theta, q]; inputs u = [de, F] (thrust, N)
    qbar = rho V^2 / 2;  CD = CD0 + CDV V/V0 + CDa alpha;  CL = CL0 + CLV V/V0 + CLa alpha
    Cm = Cm0 + CmV V/V0 + Cma alpha + Cmq q cbar/V0 + Cmde de
    V'     = -S/m qbar CD + F cos(alpha + sigma)/m + g sin(alpha - theta)
    alpha' = -S/m qbar/V CL - F sin(alpha + sigma)/(m V) + q + g cos(alpha - theta)/V
    theta' = q;   q' = S cbar/Iy qbar Cm + F lT/Iy
    outputs [V, alpha, theta, q, q', ax, az] with
    ax = S/m qbar (CL sin alpha - CD cos alpha) + F cos(sigma)/m
    az = S/m qbar (-CL cos alpha - CD sin alpha) - F sin(sigma)/m

Data: ``hfb320_1_10.asc`` as one record (uniform 0.1 s), x0 fixed at the book's values.
Start values: the book's. ``PUBLISHED``: the book software's own estimates (chapter 7
``mDefCase04``, variable ``parOEM``; see `cases/attas.py` for where the files were read).
"""

from __future__ import annotations

import numpy as np

from .textbook import Case, data_root

NAMES = ("CD0", "CDV", "CDa", "CL0", "CLV", "CLa", "Cm0", "CmV", "Cma", "Cmq", "Cmde")
THETA0 = np.array([5.67516e-03, 7.72612e-03, 6.74256e-01, -3.18267e-01, 2.60317e-01,
                   5.37576e+00, 4.98218e-02, 1.89182e-02, -4.98586e-01, -2.58439e+01,
                   -9.90687e-01])
PUBLISHED = dict(zip(NAMES, (1.22688e-01, -6.44969e-02, 3.20055e-01, -9.29113e-02,
                             1.48726e-01, 4.32785e+00, 1.11905e-01, 3.95154e-03, -9.67854e-01,
                             -3.47098e+01, -1.52913e+00)))
F0 = np.array([0.02, 0.002, 0.02, 0.02])  # start values of F, the book's (chapter 5 mDefCase04)
X0 = np.array([1.06023e+02, 1.11685e-01, 1.04887e-01, -3.32659e-03])
FILE = "jategaonkar_fvsysid2/hfb320_1_10.asc"
# geometry and mass data of the book's model
G0, S_M, SC_IY, LT_IY = 9.80665, 4.028e-3, 8.0027e-4, -7.0153e-6
V0, MASS, SIGMA, RHO, CBAR = 104.67, 7472.0, 0.0524, 0.792, 1.215


def _coefficients(x, u, p):
    V, alpha, q = x[..., 0], x[..., 1], x[..., 3]
    v = V / V0
    cd = p["CD0"] + p["CDV"] * v + p["CDa"] * alpha
    cl = p["CL0"] + p["CLV"] * v + p["CLa"] * alpha
    cm = (p["Cm0"] + p["CmV"] * v + p["Cma"] * alpha + p["Cmq"] * q * CBAR / V0
          + p["Cmde"] * u[..., 0])
    return 0.5 * RHO * V**2, cd, cl, cm


def xdot(x, u, p, c, xp):
    """Eqs. (5.86)-(5.87)."""
    V, alpha, theta, q = (x[..., i] for i in range(4))
    F = u[..., 1]
    qbar, cd, cl, cm = _coefficients(x, u, p)
    return xp.stack([
        -S_M * qbar * cd + F * xp.cos(alpha + SIGMA) / MASS + G0 * xp.sin(alpha - theta),
        (-S_M * qbar * cl - F * xp.sin(alpha + SIGMA) / MASS + G0 * xp.cos(alpha - theta)) / V
        + q,
        q,
        SC_IY * qbar * cm + LT_IY * F,
    ], axis=-1)


def obs(x, u, p, c, xp):
    """Eqs. (5.87)-(5.89)."""
    alpha = x[..., 1]
    F = u[..., 1]
    qbar, cd, cl, cm = _coefficients(x, u, p)
    sa, ca = xp.sin(alpha), xp.cos(alpha)
    return xp.stack([
        x[..., 0], alpha, x[..., 2], x[..., 3],
        SC_IY * qbar * cm + LT_IY * F,
        S_M * qbar * (cl * sa - cd * ca) + F * np.cos(SIGMA) / MASS,
        S_M * qbar * (-cl * ca - cd * sa) - F * np.sin(SIGMA) / MASS,
    ], axis=-1)


def records() -> list[dict]:
    a = np.loadtxt(data_root() / FILE)
    z = a[:, [4, 5, 6, 7, 8, 9, 10]]  # V, alpha, theta, q, qdot, ax, az (0-based columns)
    u = a[:, [1, 3]]  # de, thrust
    t = 0.1 * np.arange(len(a))
    return [{"name": "hfb320_1_10", "t": t, "u": u, "z": z, "x0": X0.copy(), "consts": {}}]


CASE = Case(
    key="tc04_oem", title="FVSysID TC04: HFB-320 longitudinal, nonlinear, 7 outputs",
    names=NAMES, theta0=THETA0, states=("V", "alpha", "theta", "q"), inputs=("de", "F"),
    outputs=("V", "alpha", "theta", "q", "qdot", "ax", "az"), xdot=xdot, obs=obs,
    records=records, files=(FILE,), published=PUBLISHED,
    source="Jategaonkar (2015) companion software, chapter07/mDefCase04.m, parOEM",
)
