"""FVSysID test case 1: ATTAS lateral-directional motion, 2 states, 5 outputs, 22 parameters.

R. V. Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, chapter 4
(output-error method), test case 1; the model is the book's Eqs. (4.90)-(4.91), restated here
from the book's model definition (``mDefCase01``; see `cases/attas.py` for where the book's
files were read):

    states  x = [p, r]; inputs u = [da, dr, beta] (beta measured, used as an input)
    p' = Lp p + Lr r + Lda da + Ldr dr + Lb beta + BX1
    r' = Np p + Nr r + Nda da + Ndr dr + Nb beta + BX2
    outputs [pdot, rdot, ay, p, r]:
        pdot = Lp p + Lr r + Lda da + Ldr dr + Lb beta + BY1   (the state bias BX1 lumped
        rdot = Np p + Nr r + Nda da + Ndr dr + Nb beta + BY2    into BY1, BX2 into BY2)
        ay   = Yp p + Yr r + Yda da + Ydr dr + Yb beta + BY3
        p + BY4,  r + BY5

Data as the book: ``fAttasAilRud1.mat`` (the aileron and the rudder manoeuvre back to back)
as ONE record on a regenerated uniform time axis ``0.04 k`` (the file clock jumps 30.08 s at
row 752), integrated from x0 = 0 (fixed; the biases absorb the offsets, book Sec. 3.5.2).
Angles and rates are converted from deg to rad; ay stays in m/s^2. Start values: the book's.
"""

from __future__ import annotations

import numpy as np

from .textbook import Case, data_root
from .attas import D2R

NAMES = ("Lp", "Lr", "Lda", "Ldr", "Lb", "Np", "Nr", "Nda", "Ndr", "Nb",
         "Yp", "Yr", "Yda", "Ydr", "Yb", "BX1", "BX2", "BY1", "BY2", "BY3", "BY4", "BY5")
# the book's starting values (mDefCase01, ``param``)
THETA0 = np.array([
    -3.53744, 0.475534, -4.93279, 0.73334, -4.34076,
    -0.086939, -0.169526, -0.192049, -0.74855, 1.55155,
    0.0364, 2.130, 0.740, 2.279, -5.193,
    0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02,
])
FILE = "jategaonkar_fvsysid2/fAttasAilRud1.mat"
DT = 0.04


def _moments(x, u, p, axis):
    """The linear roll (``axis="L"``), yaw ("N") or side-force ("Y") expression."""
    a = axis
    return (p[a + "p"] * x[..., 0] + p[a + "r"] * x[..., 1] + p[a + "da"] * u[..., 0]
            + p[a + "dr"] * u[..., 1] + p[a + "b"] * u[..., 2])


def xdot(x, u, p, c, xp):
    """Eq. (4.90)."""
    return xp.stack([_moments(x, u, p, "L") + p["BX1"], _moments(x, u, p, "N") + p["BX2"]],
                    axis=-1)


def obs(x, u, p, c, xp):
    """Eq. (4.91)."""
    return xp.stack([
        _moments(x, u, p, "L") + p["BY1"], _moments(x, u, p, "N") + p["BY2"],
        _moments(x, u, p, "Y") + p["BY3"], x[..., 0] + p["BY4"], x[..., 1] + p["BY5"],
    ], axis=-1)


def records() -> list[dict]:
    import scipy.io

    a = np.asarray(scipy.io.loadmat(str(data_root() / FILE))["fAttasAilRud1"], dtype=float)
    col = lambda k: a[:, k - 1]  # noqa: E731  (1-based, as PROVENANCE.md)
    z = np.column_stack([col(17) * D2R, col(19) * D2R, col(3), col(7) * D2R, col(9) * D2R])
    u = np.column_stack([0.5 * (col(29) - col(28)) * D2R, col(30) * D2R, col(14) * D2R])
    t = DT * np.arange(len(a))
    return [{"name": "fAttasAilRud1", "t": t, "u": u, "z": z, "x0": np.zeros(2), "consts": {}}]


CASE = Case(
    key="tc01", title="FVSysID TC01: ATTAS lateral-directional, 5 outputs", names=NAMES,
    theta0=THETA0, states=("p", "r"), inputs=("da", "dr", "beta"),
    outputs=("pdot", "rdot", "ay", "p", "r"), xdot=xdot, obs=obs, records=records,
    files=(FILE,),
)
