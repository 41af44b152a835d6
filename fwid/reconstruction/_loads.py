"""Body states and aerodynamic loads from the full nonlinear rigid-body equations.

    X Y Z = m (V' + w x V) - m R^T g          (V: velocity in body axes, g = [0, 0, g] NED)
    L M N = I w' + w x I w,   I = [[Ix, 0, -Ixz], [0, Iy, 0], [-Ixz, 0, Iz]]

(the aerodynamic loads are what the rigid body needs beyond gravity). The states are
`u v w = V`, `p q r = w` and the 3-2-1 Euler angles `phi theta psi` of `R` (body -> NED),
`psi` unwrapped (continuous in time).
"""

from __future__ import annotations

import numpy as np

from ._rotations import euler_321

#: The nonlinear terms, by name (`omit` leaves them out, to show that each matters).
TERMS = ("transport", "gravity", "gyroscopic", "product")


def inertia(vehicle: dict) -> np.ndarray:
    """The inertia matrix of `vehicle.json`'s `Ix Iy Iz Ixz` (body axes, x forward, z down)."""
    Ix, Iy, Iz, Ixz = (vehicle[k] for k in ("Ix", "Iy", "Iz", "Ixz"))
    return np.array([[Ix, 0.0, -Ixz], [0.0, Iy, 0.0], [-Ixz, 0.0, Iz]])


def rigid_body_loads(V, dV, w, dw, R, vehicle: dict, omit=()) -> tuple[np.ndarray, np.ndarray]:
    """Aerodynamic forces and moments `(N, 3)` in body axes (module docstring).

    **Arguments:**
    - `V`, `dV` `(N, 3)`: body-axis velocity (m/s) and its time derivative in body axes;
    - `w`, `dw` `(N, 3)`: body rates (rad/s) and angular accelerations;
    - `R` `(N, 3, 3)`: attitude, body -> north-east-down;
    - `vehicle`: `mass Ix Iy Iz Ixz g` (`vehicle.json`);
    - `omit`: names of `TERMS` to leave out: `transport` (w x V), `gravity` (R^T g),
      `gyroscopic` (w x I w), `product` (Ixz).

    **Returns:** `(XYZ, LMN)`.
    """
    unknown = set(omit) - set(TERMS)
    if unknown:
        raise ValueError(f"unknown terms {sorted(unknown)}; known: {TERMS}")
    m, g = vehicle["mass"], vehicle["g"]
    I = inertia({**vehicle, "Ixz": 0.0} if "product" in omit else vehicle)
    F = m * np.asarray(dV, float)
    if "transport" not in omit:
        F = F + m * np.cross(w, V)
    if "gravity" not in omit:
        F = F - m * np.einsum("nji,j->ni", R, np.array([0.0, 0.0, g]))
    Mo = np.asarray(dw, float) @ I.T
    if "gyroscopic" not in omit:
        Mo = Mo + np.cross(w, np.asarray(w) @ I.T)
    return F, Mo


def body_states(R, vel, acc, w) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body-axis velocity `V = R^T v`, its body-axis derivative `V' = R^T a - w x V`, and
    the Euler angles `(N, 3)`, of NED velocity `vel` and acceleration `acc` `(N, 3)`."""
    Rt = np.swapaxes(R, -1, -2)
    V = np.einsum("nij,nj->ni", Rt, vel)
    dV = np.einsum("nij,nj->ni", Rt, acc) - np.cross(w, V)
    return V, dV, euler_321(R)
