"""The flapping harmonics of the position in body axes, where the flapping loads are fixed.

The wings beat in the body: the flapping acceleration is a harmonic series in the flapping
phase whose coefficients are constant *in body axes*. Seen from the room, its direction
turns with the attitude, so a world-axis series with slowly wandering coefficients cannot
follow it through a manoeuvre (the pitch changes by some degrees in a second; at 70 degrees
of pitch, 8 degrees move a fifth of the X harmonic into Z). The rebuilt flapping loads
would then be modulated by the attitude, which the diagnosis reads as `flap-coupling`.

The positions are therefore smoothed twice (`split`, `compose`): once per world axis, whose
slow part alone (the white-jerk states, without the harmonics) is the reference `r(t)`; then
the remainder `z = R^T (p - r)`, in body axes (`R` body -> NED), where the harmonics have
constant coefficients and the slow part is what the reference left. The path is
`p = r + R z`, and with `R' = R [w]x`,

    p'  = r'  + R (z' + w x z)
    p'' = r'' + R (z'' + 2 w x z' + w' x z + w x (w x z)).
"""

from __future__ import annotations

import numpy as np
from jaxtyping import Float


def split(pos: Float[np.ndarray, "n 3"], ref: Float[np.ndarray, "n 3"],
          R: Float[np.ndarray, "n 3 3"]) -> Float[np.ndarray, "n 3"]:
    """The measured positions' remainder over the reference, in body axes: `R^T (p - r)`
    (NaN where `pos` is)."""
    return np.einsum("nji,nj->ni", R, np.asarray(pos, float) - ref)


def compose(ref: tuple, body: tuple, R: Float[np.ndarray, "n 3 3"],
            w: Float[np.ndarray, "n 3"], dw: Float[np.ndarray, "n 3"]
            ) -> tuple[Float[np.ndarray, "n 3"], ...]:
    """World position, velocity and acceleration of `p = r + R z` (module docstring) from the
    reference `(r, r', r'')`, the body-axis remainder `(z, z', z'')` and the attitude `R`
    with its body rates `w` and angular acceleration `dw`."""
    r, dr, ddr = ref
    z, dz, ddz = body
    rot = lambda v: np.einsum("nij,nj->ni", R, v)  # noqa: E731
    wz = np.cross(w, z)
    vel_b = dz + wz
    acc_b = ddz + 2 * np.cross(w, dz) + np.cross(dw, z) + np.cross(w, wz)
    return r + rot(z), dr + rot(vel_b), ddr + rot(acc_b)
