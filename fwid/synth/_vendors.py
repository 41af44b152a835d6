"""Tracking exports of other vendors, written to each vendor's documented layout from a pose
in north-east-down: the Vicon Nexus CSV export (`Segments` block), Qualisys QTM's 6DOF TSV
export and its MATLAB export. The readers (`fwid.reconstruction`) document the layouts; the
simulator writes its takes in them (`write_raw_flights(raw="vicon" | "qtm" | "qtm-mat")`) and
the tests write known poses in them.

Each writer takes the time base `t` (s, uniform), the positions `(n, 3)` (m, NED), the
body -> NED matrices `(n, 3, 3)` and the mask `tracked` (False: the body was lost, its cells
left empty or NaN); it writes the tracked body among `bodies`, the others standing still at
the origin, in the vendors' z-up lab frame (X forward, Y left, Z up; body axes alike) and in
millimetres.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.io import savemat
from scipy.spatial.transform import Rotation

#: NED from a z-up lab frame (Vicon's, QTM's): `x_ned = C x` (x = X, y = -Y, z = -Z).
Z_UP = np.diag([1.0, -1.0, -1.0])


def _rate(t) -> float:
    """The frame rate (Hz) of the uniform time base `t`, to a micro-hertz."""
    return float(np.round(1.0 / np.median(np.diff(t)), 6))


def ned_to_z_up(position, matrix) -> tuple[np.ndarray, np.ndarray]:
    """Z-up millimetres and body -> lab matrices (z-up body axes) of a NED pose:
    `X = 1000 C^T x_ned`, `R = C^T R_ned C`."""
    position, matrix = np.asarray(position, float), np.asarray(matrix, float)
    return 1e3 * position @ Z_UP, Z_UP @ matrix @ Z_UP


def z_up_pose(position, matrix, tracked):
    """The z-up pose, identity and zero where the body was lost (so that no NaN reaches the
    rotation maths)."""
    tracked = np.asarray(tracked, bool)
    matrix = np.where(tracked[:, None, None], np.nan_to_num(matrix), np.eye(3))
    position = np.where(tracked[:, None], np.nan_to_num(position), 0.0)
    return ned_to_z_up(position, matrix)


def _frames(t, rate) -> np.ndarray:
    """Frame numbers counted from 1 at t = 0, as Nexus and QTM count them."""
    return np.rint(np.asarray(t) * rate).astype(int) + 1


def _write(path: Path, data: bytes) -> Path:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)
    return path


def write_nexus(path, t, position, matrix, tracked, bodies=("DelFly:DelFly", "Wand:Wand"),
                body: str | None = None, euler: str | None = None) -> Path:
    """A Vicon Nexus CSV export: UTF-8 byte-order mark, CRLF, the `Segments` block (its name,
    the rate on line 2, the segment names, `Frame, Sub Frame, RX RY RZ TX TY TZ` for each
    segment, the units row `deg ... mm`), then an empty `Trajectories` block. `RX RY RZ` is
    Nexus's default helical angle (the rotation vector, deg); with `euler` (e.g. `"XYZ"`) the
    block is `Segments (Euler XYZ)` and holds intrinsic Euler angles about X, Y, Z in that
    order. `body` (default the first of `bodies`) carries the pose."""
    body = bodies[0] if body is None else body
    rate = _rate(t)
    pos, R = z_up_pose(position, matrix, tracked)
    if euler:  # the angles about X, Y, Z, in the columns RX, RY, RZ
        ang = Rotation.from_matrix(R).as_euler(euler, degrees=True)
        rot = ang[:, [euler.index(c) for c in "XYZ"]]
    else:
        rot = np.rad2deg(Rotation.from_matrix(R).as_rotvec())
    name = f"Segments (Euler {euler})" if euler else "Segments"
    lines = [name, f"{rate:g}", ",," + ",,,,,,".join(bodies) + ",,,,,",
             "Frame,Sub Frame" + ",RX,RY,RZ,TX,TY,TZ" * len(bodies),
             ",," + ",".join(["deg,deg,deg,mm,mm,mm"] * len(bodies))]
    still = ["0"] * 6
    for i, frame in enumerate(_frames(t, rate)):
        mine = [f"{v:.9f}" for v in (*rot[i], *pos[i])] if tracked[i] else [""] * 6
        cells = [c for b in bodies for c in (mine if b == body else still)]
        lines.append(",".join([str(frame), "0", *cells]))
    text = "\ufeff" + "\r\n".join(lines) + "\r\n\r\nTrajectories\r\n"
    return _write(Path(path), text.encode())


def write_qtm_tsv(path, t, position, matrix, tracked, bodies=("Wand", "DelFly"),
                  body: str = "DelFly") -> Path:
    """A QTM 6DOF TSV export: the header block (`NO_OF_FRAMES`, `FREQUENCY`, `BODY_NAMES`,
    ...), the column row `Frame, Time, <body> X Y Z Roll Pitch Yaw Residual Rot[0]..Rot[8]`
    (an empty column between bodies), one row a frame (mm, deg; the matrix column by column,
    QTM's order). A `t` starting after 0 is a trimmed export (its first frame number > 1)."""
    rate = _rate(t)
    pos, R = z_up_pose(position, matrix, tracked)
    rpy = Rotation.from_matrix(R).as_euler("XYZ", degrees=True)
    rot = R.transpose(0, 2, 1).reshape(-1, 9)  # column by column
    head = [f"NO_OF_FRAMES\t{len(t)}", "NO_OF_CAMERAS\t8", f"NO_OF_BODIES\t{len(bodies)}",
            f"FREQUENCY\t{rate:g}", "NO_OF_ANALOG\t0", "ANALOG_FREQUENCY\t0",
            "DESCRIPTION\t--", "TIME_STAMP\t2026-11-28, 10:00:00.000\t1234.5",
            "DATA_INCLUDED\t6D", "BODY_NAMES\t" + "\t".join(bodies),
            "BODY_FILTERS\t" + "\t".join(["Default"] * len(bodies)),
            "TRANSLATION_ORIGIN\t" + "\t".join(["Global"] * len(bodies)),
            "ROTATION_ORIGIN\t" + "\t".join(["Global"] * len(bodies))]
    comps = "X\tY\tZ\tRoll\tPitch\tYaw\tResidual\t" + "\t".join(f"Rot[{k}]" for k in range(9))
    head.append("Frame\tTime\t" + "\t\t".join(f"{b} {comps}" for b in bodies))
    still = "\t".join(["0"] * 6 + ["1.0"] + [str(v) for v in np.eye(3).ravel()])
    for i, frame in enumerate(_frames(t, rate)):
        mine = "\t".join([f"{v:.9f}" for v in (*pos[i], *rpy[i], 0.8, *rot[i])]
                         if tracked[i] else [""] * 16)
        cells = [mine if b == body else still for b in bodies]
        head.append(f"{frame}\t{t[i]:.5f}\t" + "\t\t".join(cells))
    return _write(Path(path), ("\n".join(head) + "\n").encode())


def write_qtm_mat(path, t, position, matrix, tracked, bodies=("Wand", "DelFly"),
                  body: str = "DelFly") -> Path:
    """A QTM MATLAB export (scipy's `savemat`): a struct named after the file with `File`,
    `FrameRate`, `Frames`, `StartFrame` and `RigidBodies` (`Bodies`, `Name`, `Positions`
    bodies x 3 x N in mm, `Rotations` bodies x 9 x N column by column, `RPYs`, `Residual`),
    NaN where the body was lost."""
    path = Path(path)
    rate = _rate(t)
    pos, R = z_up_pose(position, matrix, tracked)
    n, k, lost = len(t), len(bodies), ~np.asarray(tracked, bool)
    pos3, rpy = np.zeros((k, 3, n)), np.zeros((k, 3, n))
    rot9 = np.tile(np.eye(3).reshape(1, 9, 1), (k, 1, n))
    i = list(bodies).index(body)
    pos3[i], rot9[i] = pos.T, R.transpose(0, 2, 1).reshape(-1, 9).T
    rpy[i] = Rotation.from_matrix(R).as_euler("XYZ", degrees=True).T
    for a in (pos3, rot9, rpy):
        a[i][:, lost] = np.nan
    meas = {"File": f"{path.stem}.qtm", "FrameRate": rate, "Frames": n,
            "StartFrame": int(_frames(t[:1], rate)[0]),
            "RigidBodies": {"Bodies": k, "Name": np.array(list(bodies), dtype=object),
                            "Positions": pos3, "Rotations": rot9, "RPYs": rpy,
                            "Residual": np.ones((k, 1, n))}}
    tmp = path.with_name(f".{path.stem}.tmp.mat")
    savemat(tmp, {path.stem if path.stem.isidentifier() else "measurement": meas})
    os.replace(tmp, path)
    return path
