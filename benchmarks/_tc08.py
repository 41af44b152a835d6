"""FVSysID test case 8: an unstable aircraft's short-period motion (simulated, no process noise).

R. V. Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, Sec. 9.16.1
(the book's test case 8, model ``xdot_TC08_uAC`` / ``obs_TC08_uAC``), restated:

    states x = [w, q]; input u = [de]; U0 = 44.5695 m/s
    w' = Zw w + (U0 + Zq) q + Zde de;   q' = Mw w + Mq q + Mde de
    outputs [az, w, q] with az = Zw w + Zq q + Zde de

Zq is held at its start value, as in the book. Data: ``unStabAC_sim.asc`` (251 samples,
0.05 s); x0 = the first measured w, q (as the book). The short-period mode is unstable (the
true Mw > 0 gives a real eigenvalue of about +0.69 1/s), so a plain output-error simulation of
the 12.5 s record grows by orders of magnitude away from the data for any parameter error:
the book uses this record to motivate stabilised output error, filter error and multiple
shooting (Sec. 9.16).
"""

from __future__ import annotations

import numpy as np

from _textbook import Case, data_root

NAMES = ("Zw", "Zde", "Mw", "Mq", "Mde")
#: the book's start values (its ``param``), Zq fixed at -1.4768
THETA0 = np.array([-1.22871, -4.20491, 0.116197, -2.70670, -18.7718])
ZQ, U0 = -1.47680, 44.5695
FILE = "jategaonkar_fvsysid2/unStabAC_sim.asc"


def xdot(x, u, p, c, xp):
    w, q, de = x[..., 0], x[..., 1], u[..., 0]
    return xp.stack([p["Zw"] * w + (U0 + ZQ) * q + p["Zde"] * de,
                     p["Mw"] * w + p["Mq"] * q + p["Mde"] * de], axis=-1)


def obs(x, u, p, c, xp):
    w, q, de = x[..., 0], x[..., 1], u[..., 0]
    return xp.stack([p["Zw"] * w + ZQ * q + p["Zde"] * de, w, q], axis=-1)


def records() -> list[dict]:
    a = np.loadtxt(data_root() / FILE)
    z = a[:, [5, 2, 3]]  # az, w, q (0-based columns)
    t = 0.05 * np.arange(len(a))
    return [{"name": "unStabAC_sim", "t": t, "u": a[:, [4]], "z": z, "x0": z[0, 1:].copy(),
             "consts": {}}]


CASE = Case(
    key="tc08_unstable", title="FVSysID TC08: unstable aircraft, short period, 3 outputs",
    names=NAMES, theta0=THETA0, states=("w", "q"), inputs=("de",), outputs=("az", "w", "q"),
    xdot=xdot, obs=obs, records=records, files=(FILE,),
)
