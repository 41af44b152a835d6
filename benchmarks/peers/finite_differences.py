"""What a Python user writes instead of `fwid reconstruct`: finite differences of positions and
Euler angles (scipy's `Rotation`) after a Butterworth low-pass, loads from the same full
nonlinear rigid-body equations. The comparison row of `benchmarks/reconstruction.py`.

    python benchmarks/peers/finite_differences.py RAW_DIR OUT_DIR [--cutoff HZ] [--clock-offsets JSON]

Reads every top-level raw take of RAW_DIR (the fwid raw CSV, or a Motive export with its
`NAME.onboard.csv`), writes section-1 flights `OUT_DIR/NAME.csv` and `OUT_DIR/vehicle.json`.
Steps, per take: the Motive header skipped (7 lines), the rigid body's columns found by name,
mm -> m, y-up -> north-east-down (`x = X, y = Z, z = -Y`, the attitude `C R C^T`); dropouts
filled by linear interpolation (positions, and the Euler angles after unwrapping); Euler angles
3-2-1 from `Rotation.as_euler("ZYX")`; a zero-phase 4th-order Butterworth low-pass
(`scipy.signal.filtfilt`) at `--cutoff` (40 Hz, at most 0.4 x the rate, so the third flapping
harmonic survives, as the paper filters) on positions and angles; velocities and angular rates
by `numpy.gradient`, accelerations by `numpy.gradient` again; `X Y Z = m (V' + w x V) - m R^T g`,
`L M N = I w' + w x I w`. The autopilot log (Motive form) is put on the take's clock with the
offset given in `--clock-offsets` (a JSON `{"NAME": seconds}`: the baseline is handed the true
offset, which a user would find by eye) and interpolated linearly.
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import sys
from pathlib import Path

import numpy as np
from scipy import signal
from scipy.spatial.transform import Rotation

C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
COLUMNS = ("t", "q", "u", "w", "theta", "p", "r", "v", "phi", "psi", "de", "dr", "f",
           "X", "Y", "Z", "L", "M", "N")


def read_take(path: Path, body: str = "DelFly", offsets=None):
    """`(t, position NED (n, 3), quaternion xyzw body -> NED (n, 4), controls dict)`."""
    with open(path) as fh:
        first = fh.readline()
    if first.startswith("Format Version"):
        with open(path) as fh:
            rows = [next(csv.reader([fh.readline()])) for _ in range(7)]
        names, groups, axes = rows[3], rows[5], rows[6]
        data = np.genfromtxt(path, delimiter=",", skip_header=7)
        col = {(g, a): j for j, (n, g, a) in enumerate(zip(names, groups, axes)) if n == body}
        quat_y = data[:, [col[("Rotation", a)] for a in "XYZW"]]
        pos = data[:, [col[("Position", a)] for a in "XYZ"]] / 1000.0 @ C.T
        quat = np.column_stack([quat_y[:, :3] @ C.T, quat_y[:, 3]])  # C R C^T
        t = data[:, 1]
        log = np.genfromtxt(path.with_name(path.stem + ".onboard.csv"), delimiter=",", names=True)
        off = (offsets or {}).get(path.stem, 0.0)
        ctrl = {c: np.interp(t, log["t"] + off, log[c]) for c in ("de", "dr", "f")}
    else:
        d = np.genfromtxt(path, delimiter=",", names=True)
        t = d["t"]
        pos = np.column_stack([d["x"], d["y"], d["z"]])
        quat = np.column_stack([d["qx"], d["qy"], d["qz"], d["qw"]])
        ctrl = {c: d[c] for c in ("de", "dr", "f")}
    return t, pos, quat, ctrl


def _fill(t, x, ok):
    return np.column_stack([np.interp(t, t[ok], x[ok, j]) for j in range(x.shape[1])])


def reconstruct(t, pos, quat, ctrl, vehicle: dict, cutoff: float = 40.0) -> dict:
    """Section-1 columns from one take (finite differences, module docstring)."""
    ok = np.all(np.isfinite(pos), axis=1) & np.all(np.isfinite(quat), axis=1)
    eul = np.full((len(t), 3), np.nan)
    eul[ok] = np.unwrap(Rotation.from_quat(quat[ok]).as_euler("ZYX"), axis=0)  # psi theta phi
    pos, eul = _fill(t, pos, ok), _fill(t, eul, ok)
    dt = t[1] - t[0]
    b, a = signal.butter(4, min(cutoff, 0.4 / dt), fs=1.0 / dt)
    pos, eul = signal.filtfilt(b, a, pos, axis=0), signal.filtfilt(b, a, eul, axis=0)
    psi, theta, phi = eul.T
    dpsi, dtheta, dphi = np.gradient(eul, dt, axis=0).T
    p = dphi - dpsi * np.sin(theta)
    q = dtheta * np.cos(phi) + dpsi * np.sin(phi) * np.cos(theta)
    r = -dtheta * np.sin(phi) + dpsi * np.cos(phi) * np.cos(theta)
    R = Rotation.from_euler("ZYX", eul).as_matrix()  # body -> NED
    V = np.einsum("nji,nj->ni", R, np.gradient(pos, dt, axis=0))  # R^T v_ned
    om = np.column_stack([p, q, r])
    m, g = vehicle["mass"], vehicle["g"]
    I = np.array([[vehicle["Ix"], 0, -vehicle["Ixz"]], [0, vehicle["Iy"], 0], [-vehicle["Ixz"], 0, vehicle["Iz"]]])
    F = m * (np.gradient(V, dt, axis=0) + np.cross(om, V)) - m * g * R[:, 2, :]  # R^T e_z = row 2
    Mo = np.gradient(om, dt, axis=0) @ I.T + np.cross(om, om @ I.T)
    out = {"t": t, "q": q, "u": V[:, 0], "w": V[:, 2], "theta": theta, "p": p, "r": r,
           "v": V[:, 1], "phi": phi, "psi": psi, **ctrl}
    out.update({k: F[:, i] for i, k in enumerate("XYZ")})
    out.update({k: Mo[:, i] for i, k in enumerate("LMN")})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("raw")
    ap.add_argument("out")
    ap.add_argument("--cutoff", type=float, default=40.0)
    ap.add_argument("--clock-offsets", default=None)
    args = ap.parse_args(argv)
    raw, out = Path(args.raw), Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    vehicle = json.loads((raw / "vehicle.json").read_text())
    offsets = json.loads(Path(args.clock_offsets).read_text()) if args.clock_offsets else {}
    for path in sorted(raw.glob("*.csv")):
        if path.name.endswith(".onboard.csv"):
            continue
        cols = reconstruct(*read_take(path, offsets=offsets), vehicle, args.cutoff)
        np.savetxt(out / path.name, np.column_stack([cols[c] for c in COLUMNS]), delimiter=",",
                   header=",".join(COLUMNS), comments="", fmt="%.10g")
    shutil.copy(raw / "vehicle.json", out / "vehicle.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
