"""An exact-kinematics generator for the reconstruction tests, independent of fwid: attitude
and position are analytic functions of time (sums of sinusoids, flapping harmonics
included); rates and accelerations follow by analytic formulas and central differences of
those functions; the true loads come from the world-frame momentum balance
(`F = m (a - g)`, `M = d(R I w)/dt` rotated into body axes), not from the body-axis
equations fwid uses. Rotations by `scipy.spatial.transform`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

#: Real recordings nobody on this project wrote, beside the repository (its SOURCES.md).
REAL = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"
VEHICLE = {"mass": 0.0177, "Ix": 8.2e-5, "Iy": 9.6e-5, "Iz": 2.2e-4, "Ixz": -3.0e-5, "g": 9.81}
F0 = 12.0
C_YUP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # y-up -> NED


class Motion:
    """A nonlinear manoeuvre: large attitude changes, body rates of several rad/s, flapping
    at `F0` (harmonics 1-3) in pitch and in the position."""

    def __init__(self, scale: float = 1.0, flap: float = 1.0, seed: int = 0):
        rng = np.random.default_rng(seed)
        self.s, self.flap = scale, flap
        self.ph = rng.uniform(0, 2 * np.pi, 20)
        self.k = rng.uniform(0.93, 1.07, 20)  # frequencies scaled: no common period

    def euler(self, t):
        s, f, ph = self.s, self.flap, self.ph
        phi = s * (0.5 * np.sin(2 * np.pi * 0.4 * self.k[1] * t + ph[0]) + 0.2 * np.sin(2 * np.pi * 1.1 * self.k[2] * t + ph[1]))
        theta = 1.1 + s * (0.35 * np.sin(2 * np.pi * 0.6 * self.k[3] * t + ph[2])) + f * (
            3e-3 * np.sin(2 * np.pi * F0 * t + ph[3]) + 1e-3 * np.sin(4 * np.pi * F0 * t + ph[4]))
        psi = s * (0.9 * t + 0.6 * np.sin(2 * np.pi * 0.3 * self.k[4] * t + ph[5]))
        return np.stack([phi, theta, psi], -1)

    def R(self, t):
        return Rotation.from_euler("ZYX", self.euler(t)[..., ::-1]).as_matrix()

    def pos(self, t):
        s, f, ph = self.s, self.flap, self.ph
        x = 0.8 * t + s * 0.3 * np.sin(2 * np.pi * 0.5 * self.k[5] * t + ph[6])
        y = s * (0.4 * np.sin(2 * np.pi * 0.35 * self.k[6] * t + ph[7]))
        z = -1.0 - 0.3 * t + s * 0.2 * np.sin(2 * np.pi * 0.7 * self.k[7] * t + ph[8])
        for k, a in ((1, 1e-3), (2, 2e-4), (3, 5e-5)):
            z = z + f * a * np.sin(2 * np.pi * k * F0 * t + ph[9 + k])
            x = x + f * 0.5 * a * np.sin(2 * np.pi * k * F0 * t + ph[12 + k])
        return np.stack([x, y, z], -1)

    @staticmethod
    def _d(fn, t, h=1e-5):
        return (fn(t - 2 * h) - 8 * fn(t - h) + 8 * fn(t + h) - fn(t + 2 * h)) / (12 * h)

    def vel(self, t):
        return self._d(self.pos, t)

    def acc(self, t):
        return self._d(self.vel, t, 1e-4)

    def w(self, t):
        """Body rates from the Euler angles' rates (3-2-1 kinematics)."""
        phi, th, _ = np.moveaxis(self.euler(t), -1, 0)
        dphi, dth, dpsi = np.moveaxis(self._d(self.euler, t), -1, 0)
        return np.stack([dphi - dpsi * np.sin(th),
                         dth * np.cos(phi) + dpsi * np.cos(th) * np.sin(phi),
                         -dth * np.sin(phi) + dpsi * np.cos(th) * np.cos(phi)], -1)

    def dw(self, t):
        return self._d(self.w, t, 1e-4)

    def V(self, t):
        return np.einsum("nji,nj->ni", self.R(t), self.vel(t))

    def dV(self, t):
        return self._d(self.V, t, 1e-4)

    def loads(self, t, v=VEHICLE):
        """True aerodynamic loads in body axes, from world-frame momentum."""
        I = np.array([[v["Ix"], 0, -v["Ixz"]], [0, v["Iy"], 0], [-v["Ixz"], 0, v["Iz"]]])
        Rt = np.swapaxes(self.R(t), -1, -2)
        F = v["mass"] * np.einsum("nij,nj->ni", Rt, self.acc(t) - [0, 0, v["g"]])

        def H(tt):
            return np.einsum("nij,jk,nk->ni", self.R(tt), I, self.w(tt))

        M = np.einsum("nij,nj->ni", Rt, self._d(H, t, 1e-4))
        return F, M


def quats(R, flip: bool, rng) -> np.ndarray:
    """Scalar-first quaternions of `R`, with random sign flips when `flip`."""
    q = Rotation.from_matrix(R).as_quat()[:, [3, 0, 1, 2]]
    if flip:
        q *= rng.choice([-1.0, 1.0], size=(len(q), 1))
    return q


def noisy(motion, t, rng, pos_noise=4e-4, att_noise=np.deg2rad(0.15)):
    R = motion.R(t)
    dR = Rotation.from_rotvec(att_noise * rng.standard_normal((len(t), 3))).as_matrix()
    return motion.pos(t) + pos_noise * rng.standard_normal((len(t), 3)), R @ dR


def controls(t):
    return {"de": 0.1 * np.sin(2 * np.pi * 0.5 * t), "dr": 0.05 * np.cos(2 * np.pi * 0.3 * t),
            "f": np.full_like(t, F0)}


def write_vehicle(folder: Path, vehicle=VEHICLE) -> None:
    (Path(folder) / "vehicle.json").write_text(json.dumps(vehicle))


def write_fwid_raw(path, motion, t, *, seed=0, flip=True, lost=(), frame="ned", noise=True,
                   pos=None, R=None) -> Path:
    """A fwid raw CSV of `motion` on `t`; `lost`: index ranges left empty."""
    rng = np.random.default_rng(seed)
    if pos is None:
        pos, R = noisy(motion, t, rng) if noise else (motion.pos(t), motion.R(t))
    if frame == "y-up":
        pos, R = pos @ C_YUP, C_YUP.T @ R @ C_YUP
    q = quats(R, flip, rng)
    u = controls(t)
    rows = np.column_stack([t, pos, q, u["de"], u["dr"], u["f"]])
    lines = ["t,x,y,z,qw,qx,qy,qz,de,dr,f"]
    lost_rows = set(i for a, b in lost for i in range(a, b))
    for i, r in enumerate(rows):
        cells = [repr(float(v)) for v in r]
        if i in lost_rows:
            cells[1:8] = [""] * 7
        lines.append(",".join(cells))
    Path(path).write_text("\n".join(lines) + "\n")
    write_vehicle(Path(path).parent)
    return Path(path)


def write_motive(path, motion, t, *, offset=-3.2071, log_rate=500.0, seed=0, flip=True,
                 lost=(), bias=(0.02, -0.03, 0.01), gyro_noise=0.01, rotation="Quaternion",
                 units="Millimeters", log=True, pos=None, R=None, length_key=True,
                 time_decimals=6, missing=()) -> Path:
    """A Motive CSV export of `motion` (y-up, `units`) with a second rigid body `Wand`, and
    its autopilot log `NAME.onboard.csv` on its own clock (`t_tracking = t_onboard +
    offset`) at `log_rate`. `rotation`: `Quaternion`, or an Euler order (`XYZ`, ...: the
    angles about X, Y, Z in degrees, intrinsic in that order); `length_key`: write the
    `Length Units` key; `time_decimals`: the time column's; `missing`: index ranges of frames
    left out of the export (rows absent)."""
    rng = np.random.default_rng(seed)
    if pos is None:
        pos, R = noisy(motion, t, rng)
    pm, Rm = pos @ C_YUP, C_YUP.T @ R @ C_YUP
    scale = {"Millimeters": 1e3, "Meters": 1.0}[units]
    q = quats(Rm, flip, rng)
    euler = rotation if sorted(rotation) == ["X", "Y", "Z"] else None
    if euler:
        ang = Rotation.from_matrix(Rm).as_euler(euler, degrees=True)
        rot = ang[:, [euler.index(c) for c in "XYZ"]]
        axes, wand_rot = ["X", "Y", "Z"], [0.0, 0.0, 0.0]
    else:
        rot = np.column_stack([q[:, 1:], q[:, :1]])
        axes, wand_rot = ["X", "Y", "Z", "W"], [0.0, 0.0, 0.0, 1.0]
    k = len(axes)
    rate = 1 / (t[1] - t[0])
    head = (f"Format Version,1.23,Take Name,{Path(path).stem},Take Notes,,Capture Frame Rate,"
            f"{rate:.6f},Export Frame Rate,{rate:.6f},Capture Start Time,2026-11-25 04.01.02.123 PM,"
            f"Capture Start Frame,0,Total Frames in Take,{len(t)},Total Exported Frames,{len(t)},"
            f"Rotation Type,{rotation}" + (f",Length Units,{units}" if length_key else "")
            + ",Coordinate Space,Global")
    lines = [head, "",
             ",Type," + ",".join(["Rigid Body"] * (k + 4) + ["Rigid Body"] * (k + 3)),
             ",Name," + ",".join(["Wand"] * (k + 3) + ["DelFly"] * (k + 4)),
             ",ID," + ",".join(["2"] * (k + 3) + ["1"] * (k + 4)),
             ",," + ",".join(["Rotation"] * k + ["Position"] * 3 + ["Rotation"] * k
                            + ["Position"] * 3 + ["Mean Marker Error"]),
             "Frame,Time (Seconds)," + ",".join((axes + ["X", "Y", "Z"]) * 2 + [""])]
    lost_rows = set(i for a, b in lost for i in range(a, b))
    gone = set(i for a, b in missing for i in range(a, b))
    for i in range(len(t)):
        if i in gone:
            continue
        wand = wand_rot + [100.0 + 1e-3 * i, 5.0, 20.0]
        body = [*rot[i], *(pm[i] * scale)]
        time = np.floor(t[i] * 10**time_decimals + 1e-6) / 10**time_decimals  # truncated
        cells = ([str(i), f"{time:.{time_decimals}f}"] + [f"{v:.6f}" for v in wand]
                 + [f"{v:.6f}" for v in body] + ["0.1"])
        if i in lost_rows:
            cells[2 + k + 3:2 + 2 * (k + 3)] = [""] * (k + 3)
        lines.append(",".join(cells))
    Path(path).write_text("\n".join(lines) + "\n")
    write_vehicle(Path(path).parent)
    if log:
        tl = np.arange(t[0] - offset - 0.5, t[-1] - offset + 0.5, 1 / log_rate)
        g = motion.w(tl + offset) + np.asarray(bias) + gyro_noise * rng.standard_normal((len(tl), 3))
        u = controls(tl + offset)
        rows = np.column_stack([tl, u["de"], u["dr"], u["f"], g])
        np.savetxt(Path(path).with_name(Path(path).stem + ".onboard.csv"), rows, delimiter=",",
                   header="t,de,dr,f,p,q,r", comments="", fmt="%.12g")
    return Path(path)
