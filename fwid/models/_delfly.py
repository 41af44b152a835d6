"""The DelFly cycle-averaged grey-box models: longitudinal (Eq. 7) and lateral (Eqs. 8-9).

Aerodynamics linear in the perturbation states (Eqs. 1-6) inside the linearised rigid-body
equations of motion, with a bias term per equation (the paper's unit input `b`).
"""

from __future__ import annotations

import jax.numpy as jnp

from ._greybox import GreyBoxModel

# Table 1 and Table 4 of the paper: nominal values (the estimator starts from least squares).
TABLE1 = dict(
    Xq=3.05e-3, Xu=-3.39e-2, Xw=1.81e-2, Xde=2.53e-2,
    Zq=-1.31e-2, Zu=-3.21e-2, Zw=-7.74e-2, Zde=-9.67e-2,
    Mq=-1.03e-3, Mu=3.90e-3, Mw=2.59e-3, Mde=-6.96e-3,
)
TABLE4 = dict(
    Yp=6.54e-4, Yr=-2.59e-3, Yv=-9.92e-2, Ydr=-6.96e-2,
    Lp=-7.14e-6, Lr=3.09e-5, Lv=-4.47e-5, Ldr=6.89e-5,
    Np=-1.98e-5, Nr=-4.79e-4, Nv=-1.45e-3, Ndr=-2.10e-3,
)
LON_BIASES = ("bq", "bu", "bw", "btheta")
LAT_BIASES = ("bp", "br", "bv", "bphi")


def _lon_aero(x, u, p, c):
    """Cycle-averaged longitudinal aerodynamics, Eqs. (1), (3), (5), perturbation part."""
    q, uu, w, _ = x
    de = u[0]
    X = p["Xq"] * q + p["Xu"] * uu + p["Xw"] * w + p["Xde"] * de
    Z = p["Zq"] * q + p["Zu"] * uu + p["Zw"] * w + p["Zde"] * de
    M = p["Mq"] * q + p["Mu"] * uu + p["Mw"] * w + p["Mde"] * de
    return jnp.stack([X, Z, M])


def _lon_f(x, u, p, c):
    """Linearised longitudinal EOM, Eq. (7), states (dq, du, dw, dtheta), input (dde, 1)."""
    q, _, _, th = x
    X, Z, M = _lon_aero(x, u, p, c)
    m, g = c["mass"], c["g"]
    return jnp.stack([
        M / c["Iy"] + p["bq"],
        X / m - c["w0"] * q - g * jnp.cos(c["theta0"]) * th + p["bu"],
        Z / m + c["u0"] * q - g * jnp.sin(c["theta0"]) * th + p["bw"],
        q + p["btheta"],
    ])


def _lat_aero(x, u, p, c):
    """Cycle-averaged lateral aerodynamics, Eqs. (2), (4), (6), perturbation part."""
    pp, r, v, _ = x
    dr = u[0]
    Y = p["Yp"] * pp + p["Yr"] * r + p["Yv"] * v + p["Ydr"] * dr
    L = p["Lp"] * pp + p["Lr"] * r + p["Lv"] * v + p["Ldr"] * dr
    N = p["Np"] * pp + p["Nr"] * r + p["Nv"] * v + p["Ndr"] * dr
    return jnp.stack([Y, L, N])


def _lat_f(x, u, p, c):
    """Linearised lateral EOM, Eq. (8), states (dp, dr, dv, dphi), input (ddr, 1)."""
    pp, r, _, phi = x
    Y, L, N = _lat_aero(x, u, p, c)
    Ix, Iz, Ixz = c["Ix"], c["Iz"], c["Ixz"]
    Ic = Ix * Iz - Ixz**2
    return jnp.stack([
        (Iz * L + Ixz * N) / Ic + p["bp"],
        (Ixz * L + Ix * N) / Ic + p["br"],
        Y / c["mass"] + c["w0"] * pp - c["u0"] * r + c["g"] * jnp.cos(c["theta0"]) * phi
        + p["bv"],
        pp + jnp.tan(c["theta0"]) * r + p["bphi"],
    ])


def longitudinal(params: dict | None = None, *, biases: bool = True) -> GreyBoxModel:
    """The cycle-averaged longitudinal DelFly model, Eq. (7) with Eqs. (1), (3), (5).

    States and outputs `q u w theta` (perturbations from trim), input `de`; parameters
    `Xq Xu Xw Xde Zq Zu Zw Zde Mq Mu Mw Mde` and the biases `bq bu bw btheta`. Constants:
    `mass Iy g u0 w0 theta0` (from `vehicle.json` and the trim).

    **Arguments:**

    - `params`: values of the parameters by name, overriding the defaults (the paper's
      Table 1 values, biases 0).
    - `biases`: estimate the bias terms (the paper's unit input; flight-specific) with the
      aerodynamic parameters; `False` holds them at their values.

    **Returns:** a [`fwid.GreyBoxModel`][].
    """
    p = dict(TABLE1)
    p.update({b: 0.0 for b in LON_BIASES})
    p.update(params or {})
    free = tuple(TABLE1) + (LON_BIASES if biases else ())
    return GreyBoxModel(
        _lon_f, states=("q", "u", "w", "theta"), inputs=("de",), params=p, free=free,
        constants=("mass", "Iy", "g", "u0", "w0", "theta0"),
        forces=_lon_aero, force_names=("X", "Z", "M"), local=LON_BIASES, name="lon",
    )


def lateral(params: dict | None = None, *, biases: bool = True) -> GreyBoxModel:
    """The cycle-averaged lateral DelFly model, Eq. (8) with Eqs. (2), (4), (6).

    States and outputs `p r v phi` (perturbations), input `dr`; parameters
    `Yp Yr Yv Ydr Lp Lr Lv Ldr Np Nr Nv Ndr` and the biases `bp br bv bphi`. Constants:
    `mass Ix Iz Ixz g u0 w0 theta0`. Heading follows from Eq. (9), see [`fwid.heading_rate`][].

    **Arguments:**

    - `params`: values of the parameters by name, overriding the defaults (the paper's
      Table 4 values, biases 0).
    - `biases`: estimate the bias terms (flight-specific) with the aerodynamic parameters;
      `False` holds them at their values.

    **Returns:** a [`fwid.GreyBoxModel`][].
    """
    p = dict(TABLE4)
    p.update({b: 0.0 for b in LAT_BIASES})
    p.update(params or {})
    free = tuple(TABLE4) + (LAT_BIASES if biases else ())
    return GreyBoxModel(
        _lat_f, states=("p", "r", "v", "phi"), inputs=("dr",), params=p, free=free,
        constants=("mass", "Ix", "Iz", "Ixz", "g", "u0", "w0", "theta0"),
        forces=_lat_aero, force_names=("Y", "L", "N"), local=LAT_BIASES, name="lat",
    )


def heading_rate(r, theta0):
    """Linearised yaw kinematics, Eq. (9): `dpsi/dt = dr / cos(theta0)` (about `phi0 = r0 = 0`).

    **Arguments:**

    - `r`: the yaw rate perturbation [rad/s].
    - `theta0`: the trim pitch angle [rad].

    **Returns:** the heading rate `dpsi/dt` [rad/s].
    """
    return r / jnp.cos(theta0)
