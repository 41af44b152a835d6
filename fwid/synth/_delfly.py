"""The "true" DelFly II of fwid's simulator: mass, inertia, trim and aerodynamic parameters.

Plain numpy on purpose: this is the reference that fwid's (JAX) estimator is tested against,
so it shares no code with `fwid.models` / `fwid.simulate`.

Aerodynamic derivatives are the paper's estimates: Table 1 (longitudinal, Eqs. 1, 3, 5),
Table 4 (lateral, Eqs. 2, 4, 6) and Table 7 (longitudinal flapping Fourier coefficients,
Eq. 12). The lateral flapping coefficients (`ay* by* al* bl* an* bn*`) are not in the paper
(it models the longitudinal flapping only); they are invented, small and plausible: about
10 % of the corresponding longitudinal amplitudes for the side force and yawing moment and a
few 1e-6 N m for the rolling moment (the wings flap symmetrically about the x-z plane, so
any lateral flapping load comes from small asymmetries).

**How mass, inertia and trim were found.** The paper gives neither the mass/inertia nor the
trim that go with Tables 1 and 4, only the eigenvalues of the resulting models (Tables 3 and
6). With one trim (u0, w0, theta0) shared by both axes there are eight unknowns
(m, Iy, Ix, Iz, Ixz, u0, w0, theta0) and eight equations: the four characteristic-polynomial
coefficients of the longitudinal matrix (Eq. 7) must equal those of Table 3, and the four of
the lateral matrix (Eq. 8) those of Table 6. Solving that square system
(`scipy.optimize.least_squares` from 400 random starts, then `scipy.optimize.fsolve`,
relative residuals < 1e-15) gives three isolated real solutions; only one is physical (the
others have backward flight or a nearly inverted attitude). It is the one hard-coded below:

- m = 17.71 g (the paper: "approximately 18 g"), Iy = 9.55e-5 kg m^2,
- Ix = 8.18e-7, Iz = 2.18e-4, Ixz = -1.87e-6 kg m^2 (Ix*Iz - Ixz^2 > 0),
- u0 = 0.665 m/s, w0 = 0.903 m/s (airspeed 1.12 m/s, angle of attack 53.6 deg),
- theta0 = 72.6 deg (the paper: "~70-80 deg in slow forward flight"), i.e. a 19 deg climb.

Both tables are then reproduced to the printed precision (relative error < 1e-8).

Alternatives that were rejected: (a) level flight (flight-path angle 0) fixes the
longitudinal problem uniquely (m = 17.46 g, Iy = 9.63e-5, airspeed 0.585 m/s, theta0 =
73.0 deg), but then no inertia (Ix, Iz, Ixz) reproduces Table 6 at the same trim (best
least-squares fit: -1.45 +/- 5.71i, -6.77 +/- 1.14i instead of -1.32 +/- 5.76i, -5.07,
-9.16); Table 6 then needs its own trim (theta0 = 78.0 deg at the same airspeed). (b) Every
exact solution, whatever the trim, needs a small roll inertia, Ix ~ 0.7-1.2e-6 kg m^2. That
is below a rough geometric estimate (~4e-6) but consistent with the paper's own lateral data
(Figs. 9-10: roll rates of 500-800 deg/s produced by rolling moments of only ~1e-4 N m).
"""

from __future__ import annotations

import dataclasses

import numpy as np

#: Longitudinal cycle-averaged parameters (paper Eqs. 1, 3, 5; Table 1).
LON_PARAMS = ("Xq", "Xu", "Xw", "Xde", "Zq", "Zu", "Zw", "Zde", "Mq", "Mu", "Mw", "Mde")
#: Lateral cycle-averaged parameters (paper Eqs. 2, 4, 6; Table 4).
LAT_PARAMS = ("Yp", "Yr", "Yv", "Ydr", "Lp", "Lr", "Lv", "Ldr", "Np", "Nr", "Nv", "Ndr")


def _fourier_names(axes: str) -> tuple[str, ...]:
    return tuple(f"{ab}{c}{n}" for c in axes for n in (1, 2, 3) for ab in ("a", "b"))


#: Longitudinal flapping Fourier coefficients (Eq. 12; Table 7): `a` sine, `b` cosine.
FLAP_LON_PARAMS = _fourier_names("xzm")
#: Lateral flapping Fourier coefficients (not in the paper; invented, see module docstring).
FLAP_LAT_PARAMS = _fourier_names("yln")
#: Every aerodynamic parameter of the truth model, by its report name.
ALL_PARAMS = LON_PARAMS + LAT_PARAMS + FLAP_LON_PARAMS + FLAP_LAT_PARAMS

#: Force/moment order used throughout `fwid.synth`.
FORCES = ("X", "Y", "Z", "L", "M", "N")
#: Perturbation-state order of the simulator (lon block, lat block, heading).
STATES = ("q", "u", "w", "theta", "p", "r", "v", "phi", "psi")


@dataclasses.dataclass(frozen=True)
class DelFly:
    """Parameters of the simulated DelFly II (SI units, radians).

    Vehicle: `mass`, `Ix`, `Iy`, `Iz`, `Ixz`, `g`. Trim (linearisation point, Eqs. 1-9):
    `u0`, `w0`, `theta0`, plus the trim deflections `de0`, `dr0` and the nominal flapping
    frequency `f0`. Aerodynamics: the names of `ALL_PARAMS` (Tables 1, 4, 7 and the invented
    lateral flapping coefficients).
    """

    # vehicle: solved so that Tables 3 and 6 are reproduced (see the module docstring)
    mass: float = 1.771097079643e-02
    Iy: float = 9.553260331995e-05
    Ix: float = 8.180522661748e-07
    Iz: float = 2.178220245331e-04
    Ixz: float = -1.874616311783e-06
    g: float = 9.81
    # trim
    u0: float = 6.654849824155e-01
    w0: float = 9.033231395904e-01
    theta0: float = 1.267112136927e00
    de0: float = 0.04
    dr0: float = 0.0
    f0: float = 12.5
    # Table 1
    Xq: float = 3.05e-03
    Xu: float = -3.39e-02
    Xw: float = 1.81e-02
    Xde: float = 2.53e-02
    Zq: float = -1.31e-02
    Zu: float = -3.21e-02
    Zw: float = -7.74e-02
    Zde: float = -9.67e-02
    Mq: float = -1.03e-03
    Mu: float = 3.90e-03
    Mw: float = 2.59e-03
    Mde: float = -6.96e-03
    # Table 4
    Yp: float = 6.54e-04
    Yr: float = -2.59e-03
    Yv: float = -9.92e-02
    Ydr: float = -6.96e-02
    Lp: float = -7.14e-06
    Lr: float = 3.09e-05
    Lv: float = -4.47e-05
    Ldr: float = 6.89e-05
    Np: float = -1.98e-05
    Nr: float = -4.79e-04
    Nv: float = -1.45e-03
    Ndr: float = -2.10e-03
    # Table 7 (a: sine, b: cosine; harmonics 1..3)
    ax1: float = -7.09e-03
    bx1: float = 8.89e-02
    ax2: float = 3.09e-02
    bx2: float = 2.75e-02
    ax3: float = 7.32e-03
    bx3: float = 1.83e-02
    az1: float = 4.02e-02
    bz1: float = -5.64e-02
    az2: float = -5.51e-03
    bz2: float = 4.24e-02
    az3: float = 1.42e-02
    bz3: float = 1.29e-02
    am1: float = -3.58e-04
    bm1: float = 3.20e-03
    am2: float = -5.15e-04
    bm2: float = 2.69e-03
    am3: float = 5.44e-04
    bm3: float = 8.35e-04
    # lateral flapping: invented (not in the paper), small and plausible
    ay1: float = 4.0e-03
    by1: float = -9.0e-03
    ay2: float = 3.0e-03
    by2: float = 2.0e-03
    ay3: float = -1.0e-03
    by3: float = 1.5e-03
    al1: float = -2.0e-06
    bl1: float = 3.0e-06
    al2: float = 1.5e-06
    bl2: float = -1.0e-06
    al3: float = 5.0e-07
    bl3: float = 4.0e-07
    an1: float = 1.5e-04
    bn1: float = -2.5e-04
    an2: float = -1.0e-04
    bn2: float = 8.0e-05
    an3: float = 4.0e-05
    bn3: float = -3.0e-05

    # ------------------------------------------------------------------ views
    def params(self, names=ALL_PARAMS) -> dict[str, float]:
        """The aerodynamic parameters by name (default: all of `ALL_PARAMS`)."""
        return {k: float(getattr(self, k)) for k in names}

    def vehicle(self) -> dict[str, float]:
        """Mass and inertia as in `vehicle.json` (the flight-data format)."""
        return {k: float(getattr(self, k)) for k in ("mass", "Ix", "Iy", "Iz", "Ixz", "g")}

    def trim(self) -> dict[str, float]:
        """The trim of every flight column, as a sidecar's `{"trim": ...}` (`<col>0` keys).

        Forces are the cycle-averaged trim loads of Eqs. 1 and 3 (`X0 = m g sin theta0`,
        `Z0 = -m g cos theta0`); moments and lateral quantities are zero.
        """
        m, g, th = self.mass, self.g, self.theta0
        return {
            "q0": 0.0,
            "u0": float(self.u0),
            "w0": float(self.w0),
            "theta0": float(th),
            "p0": 0.0,
            "r0": 0.0,
            "v0": 0.0,
            "phi0": 0.0,
            "psi0": 0.0,
            "de0": float(self.de0),
            "dr0": float(self.dr0),
            "f0": float(self.f0),
            "X0": float(m * g * np.sin(th)),
            "Y0": 0.0,
            "Z0": float(-m * g * np.cos(th)),
            "L0": 0.0,
            "M0": 0.0,
            "N0": 0.0,
        }

    def fourier(self, force: str) -> np.ndarray:
        """Flapping coefficients of `force` (one of X Y Z L M N) as a (3, 2) array of
        `[a_n, b_n]` rows, n = 1, 2, 3 (Eq. 12)."""
        c = force.lower()
        return np.array([[getattr(self, f"a{c}{n}"), getattr(self, f"b{c}{n}")] for n in (1, 2, 3)])

    def replace(self, **changes) -> DelFly:
        """A copy with some fields changed (a frozen dataclass)."""
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ linear models
    def lon_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """`(A, B)` of Eq. 7 (states dq du dw dtheta, input dde), without the bias column."""
        return lon_matrices(self)

    def lat_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """`(A, B)` of Eq. 8 (states dp dr dv dphi, input ddr), without the bias column."""
        return lat_matrices(self)

    def eigenvalues(self, axis: str = "lon") -> np.ndarray:
        """Eigenvalues of the lon (Eq. 7) or lat (Eq. 8) matrix, sorted (cf. Tables 3, 6)."""
        A = (self.lon_matrices() if axis == "lon" else self.lat_matrices())[0]
        return np.sort_complex(np.linalg.eigvals(A))


def lon_matrices(p: DelFly) -> tuple[np.ndarray, np.ndarray]:
    """Paper Eq. 7: the longitudinal cycle-averaged model with Eqs. 1, 3, 5 substituted.

    States `[dq, du, dw, dtheta]`, input `dde`:

        dq'     = (Mq dq + Mu du + Mw dw + Mde dde) / Iy
        du'     = (Xq/m - w0) dq + Xu/m du + Xw/m dw - g cos(theta0) dtheta + Xde/m dde
        dw'     = (Zq/m + u0) dq + Zu/m du + Zw/m dw - g sin(theta0) dtheta + Zde/m dde
        dtheta' = dq
    """
    m, Iy, g, th = p.mass, p.Iy, p.g, p.theta0
    A = np.array(
        [
            [p.Mq / Iy, p.Mu / Iy, p.Mw / Iy, 0.0],
            [p.Xq / m - p.w0, p.Xu / m, p.Xw / m, -g * np.cos(th)],
            [p.Zq / m + p.u0, p.Zu / m, p.Zw / m, -g * np.sin(th)],
            [1.0, 0.0, 0.0, 0.0],
        ]
    )
    B = np.array([[p.Mde / Iy], [p.Xde / m], [p.Zde / m], [0.0]])
    return A, B


def lat_matrices(p: DelFly) -> tuple[np.ndarray, np.ndarray]:
    """Paper Eq. 8: the lateral cycle-averaged model with Eqs. 2, 4, 6 substituted.

    States `[dp, dr, dv, dphi]`, input `ddr`; with `Ic = Ix Iz - Ixz^2`:

        dp'   = (Iz L + Ixz N) / Ic
        dr'   = (Ixz L + Ix N) / Ic
        dv'   = (Yp/m + w0) dp + (Yr/m - u0) dr + Yv/m dv + g cos(theta0) dphi + Ydr/m ddr
        dphi' = dp + tan(theta0) dr

    where `L = Lp dp + Lr dr + Lv dv + Ldr ddr` and likewise `N`.
    """
    m, g, th = p.mass, p.g, p.theta0
    Ic = p.Ix * p.Iz - p.Ixz**2
    L = np.array([p.Lp, p.Lr, p.Lv, 0.0, p.Ldr])
    N = np.array([p.Np, p.Nr, p.Nv, 0.0, p.Ndr])
    rp = (p.Iz * L + p.Ixz * N) / Ic
    rr = (p.Ixz * L + p.Ix * N) / Ic
    rv = np.array([p.Yp / m + p.w0, p.Yr / m - p.u0, p.Yv / m, g * np.cos(th), p.Ydr / m])
    rphi = np.array([1.0, np.tan(th), 0.0, 0.0, 0.0])
    M = np.vstack([rp, rr, rv, rphi])
    return M[:, :4], M[:, 4:]


def force_matrix(p: DelFly) -> np.ndarray:
    """`G` (9 x 6): state derivatives produced by perturbation forces/moments
    `[dX, dY, dZ, dL, dM, dN]` (the inertial part of Eqs. 7-8): `x' = ... + G dF`."""
    m = p.mass
    Ic = p.Ix * p.Iz - p.Ixz**2
    G = np.zeros((9, 6))
    G[0, 4] = 1.0 / p.Iy  # q  <- M
    G[1, 0] = 1.0 / m  # u  <- X
    G[2, 2] = 1.0 / m  # w  <- Z
    G[4, 3], G[4, 5] = p.Iz / Ic, p.Ixz / Ic  # p <- L, N
    G[5, 3], G[5, 5] = p.Ixz / Ic, p.Ix / Ic  # r <- L, N
    G[6, 1] = 1.0 / m  # v  <- Y
    return G


def kinematic_matrix(p: DelFly) -> np.ndarray:
    """`K` (9 x 9): the non-aerodynamic part of Eqs. 7-9 (gravity, trim-velocity and
    kinematic terms): `x' = K x + G dF`, with `dF` the aerodynamic perturbation loads."""
    g, th, u0, w0 = p.g, p.theta0, p.u0, p.w0
    K = np.zeros((9, 9))
    K[1, 0], K[1, 3] = -w0, -g * np.cos(th)  # u' = -w0 q - g cos th0 theta
    K[2, 0], K[2, 3] = u0, -g * np.sin(th)  # w' = u0 q - g sin th0 theta
    K[3, 0] = 1.0  # theta' = q
    K[6, 4], K[6, 5], K[6, 7] = w0, -u0, g * np.cos(th)  # v' = w0 p - u0 r + g cos th0 phi
    K[7, 4], K[7, 5] = 1.0, np.tan(th)  # phi' = p + tan th0 r
    K[8, 5] = 1.0 / np.cos(th)  # psi' = r / cos th0 (Eq. 9)
    return K


def aero_matrices(p: DelFly) -> tuple[np.ndarray, np.ndarray]:
    """`(Fx, Fu)`: linear cycle-averaged aerodynamic perturbation loads of Eqs. 1-6,
    `dF = Fx x + Fu [dde, ddr]` with `dF = [dX, dY, dZ, dL, dM, dN]` and `x` in `STATES`
    order."""
    Fx = np.zeros((6, 9))
    Fu = np.zeros((6, 2))
    for i, c in ((0, "X"), (2, "Z"), (4, "M")):
        Fx[i, :3] = [getattr(p, c + "q"), getattr(p, c + "u"), getattr(p, c + "w")]
        Fu[i, 0] = getattr(p, c + "de")
    for i, c in ((1, "Y"), (3, "L"), (5, "N")):
        Fx[i, 4:7] = [getattr(p, c + "p"), getattr(p, c + "r"), getattr(p, c + "v")]
        Fu[i, 1] = getattr(p, c + "dr")
    return Fx, Fu


def state_space(p: DelFly) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(A, B, G)` of the 9-state decoupled model (Eqs. 7-9 side by side; states `STATES`,
    inputs `[dde, ddr]`): `x' = A x + B u + G dF_extra` where `dF_extra` are aerodynamic
    loads beyond the linear cycle-averaged model (flapping, unmodelled effects)."""
    K = kinematic_matrix(p)
    G = force_matrix(p)
    Fx, Fu = aero_matrices(p)
    return K + G @ Fx, G @ Fu, G


#: The true parameters of fwid's simulated DelFly II.
DELFLY = DelFly()
