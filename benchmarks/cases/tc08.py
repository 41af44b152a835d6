"""FVSysID test case 8: an open-loop unstable aircraft, short-period motion, simulated data.

R. V. Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, chapter 9
(unstable aircraft), test case 8; the model restated from the book's model definition
(``mDefCase08``, ``xdot_TC08_uAC``, ``obs_TC08_uAC``):

    states x = [w, q]; input u = [de]; U0 = 44.5695 m/s
    w' = Zw w + (U0 + Zq) q + Zde de
    q' = Mw w + Mq q + Mde de
    outputs [az, w, q] with az = Zw w + Zq q + Zde de

Data: ``unStabAC_sim.asc`` (simulated, no process noise; 251 samples at 0.05 s), x0 = 0
(fixed, as the book). Start values: the book's (``param`` of ``mDefCase08``); Zq is fixed
at its start value -1.4768, as the book does (``parFlag``). ``TRUE``: the
values the data were simulated with; the eigenvalues they give are -5.825 and
+0.693 1/s. Plain output error diverges from the unstable start and ends at a stable model
(the book's known wrong answer); `fwid.fit(..., method="multiple-shooting")` reaches the truth.
"""

from __future__ import annotations

import numpy as np

from .textbook import Case, data_root

NAMES = ("Zw", "Zq", "Zde", "Mw", "Mq", "Mde")
FREE = ("Zw", "Zde", "Mw", "Mq", "Mde")  # Zq fixed at its start value, as the book
THETA0 = np.array([-1.22871, -1.47680, -4.20491, 0.116197, -2.70670, -18.7718])
ZQ = float(THETA0[1])  # Zq, fixed
TRUE = {"Zw": -1.4249, "Mw": 0.2163, "Mq": -3.7067}
TRUE_EIGENVALUES = (-5.825, 0.693)
U0 = 44.5695
FILE = "jategaonkar_fvsysid2/unStabAC_sim.asc"
DT = 0.05


def xdot(x, u, p, c, xp):
    w, q = x[..., 0], x[..., 1]
    de = u[..., 0]
    return xp.stack([p["Zw"] * w + (U0 + p["Zq"]) * q + p["Zde"] * de,
                     p["Mw"] * w + p["Mq"] * q + p["Mde"] * de], axis=-1)


def obs(x, u, p, c, xp):
    w, q = x[..., 0], x[..., 1]
    az = p["Zw"] * w + p["Zq"] * q + p["Zde"] * u[..., 0]
    return xp.stack([az, w, q], axis=-1)


def records() -> list[dict]:
    a = np.loadtxt(data_root() / FILE)
    z = a[:, [5, 2, 3]]  # az, w, q (0-based columns)
    u = a[:, [4]]  # de
    t = DT * np.arange(len(a))
    return [{"name": "unStabAC_sim", "t": t, "u": u, "z": z, "x0": np.zeros(2), "consts": {}}]


def eigenvalues(p: dict) -> np.ndarray:
    """The short-period eigenvalues of the estimates `p` (sorted, real here)."""
    A = np.array([[p["Zw"], U0 + p["Zq"]], [p["Mw"], p["Mq"]]])
    return np.sort(np.linalg.eigvals(A).real)


CASE = Case(
    key="tc08", title="FVSysID TC08: unstable aircraft, short period, 3 outputs",
    names=NAMES, theta0=THETA0, states=("w", "q"), inputs=("de",),
    outputs=("az", "w", "q"), xdot=xdot, obs=obs, records=records, files=(FILE,),
    published=TRUE, source="the values the data were simulated with", free=FREE,
)
