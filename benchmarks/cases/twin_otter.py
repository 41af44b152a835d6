"""SIDPAC's Twin Otter longitudinal output-error demo: the `tlonss` state-space model.

E. A. Morelli, SIDPAC (NASA LAR-16100-1), demo ``oe_demo.m`` with the model ``tlonss.m``, as
described in ``sidpac_v1_twin_otter/PROVENANCE.md``; see also Klein and Morelli, *Aircraft
System Identification*, AIAA 2006, chapter 6:

    states x = [alpha, q] (rad, rad/s); inputs u = [de (rad), 1]
    alpha' = p1 alpha + p2 q + p3 de + p4;   q' = p5 alpha + p6 q + p7 de + p8
    outputs [alpha, q, az (g)] with az = V/g (p1 alpha + (p2 - 1) q + p3 de) + p9

V = mean airspeed of the record (ft/s), g = 32.174 ft/s^2. Data: ``oe_lon_example.mat``
(manoeuvre 020213f1_019, 0.02 s). The demo starts from an equation-error fit of the
differentiated measured alpha and q on [alpha, q, de, 1] (p9 = -1); this module does the same
with a central difference. x0 is the first sample of alpha and q (SIDPAC smooths it first).
SIDPAC's saved results (`totter_results.mat`) are for its nonlinear model, not `tlonss`, so
there are no published values to compare with.
"""

from __future__ import annotations

import numpy as np

from .textbook import Case, data_root

NAMES = tuple(f"p{i}" for i in range(1, 10))
FILE = "sidpac_v1_twin_otter/oe_lon_example.mat"
G = 32.174


def xdot(x, u, p, c, xp):
    a, q, de, one = x[..., 0], x[..., 1], u[..., 0], u[..., 1]
    return xp.stack([p["p1"] * a + p["p2"] * q + p["p3"] * de + p["p4"] * one,
                     p["p5"] * a + p["p6"] * q + p["p7"] * de + p["p8"] * one], axis=-1)


def obs(x, u, p, c, xp):
    a, q, de, one = x[..., 0], x[..., 1], u[..., 0], u[..., 1]
    az = c["vtg"] * (p["p1"] * a + (p["p2"] - 1.0) * q + p["p3"] * de) + p["p9"] * one
    return xp.stack([a, q, az], axis=-1)


def records() -> list[dict]:
    import scipy.io

    d = scipy.io.loadmat(str(data_root() / FILE))
    fdata, t = np.asarray(d["fdata"], float), np.asarray(d["t"], float).ravel()
    z = np.column_stack([fdata[:, 3] * np.pi / 180, fdata[:, 5] * np.pi / 180, fdata[:, 12]])
    u = np.column_stack([fdata[:, 13] * np.pi / 180, np.ones(len(t))])
    return [{"name": "020213f1_019", "t": t - t[0], "u": u, "z": z, "x0": z[0, :2].copy(),
             "consts": {"vtg": float(np.mean(fdata[:, 1])) / G}}]


def equation_error_start() -> np.ndarray:
    """oe_demo's start: least squares of the differentiated alpha, q on [alpha, q, u]."""
    r = records()[0]
    zd = np.gradient(r["z"][:, :2], r["t"], axis=0)
    X = np.column_stack([r["z"][:, :2], r["u"]])
    coef, *_ = np.linalg.lstsq(X, zd, rcond=None)
    return np.concatenate([coef[:, 0], coef[:, 1], [-1.0]])


def case() -> Case:
    """The case, its start values computed from the data (so only when they are there)."""
    return Case(
        key="twin_otter_tlonss", title="SIDPAC Twin Otter tlonss: alpha, q, az",
        names=NAMES, theta0=equation_error_start(), states=("alpha", "q"),
        inputs=("de", "one"), outputs=("alpha", "q", "az"), xdot=xdot, obs=obs,
        records=records, files=(FILE,),
    )
