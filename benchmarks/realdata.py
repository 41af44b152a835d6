"""Real Flapper Drone flights (`../shared/realdata`, TU Delft Cyberzoo data set; see its
SOURCES.md) through `fwid reconstruct --map docs/guide/flapper.toml`: the cycle-averaged
specific force reconstructed from the pose against the onboard accelerometer, beside a naive
Savitzky-Golay differentiation of the same pose, and the time taken.

    python benchmarks/realdata.py [--out benchmarks/results/realdata.md]

The naive peer is what a lab writes by hand: the logged pose (z-up, ZYX Euler angles in
degrees), handed the convention fwid found from the accelerometer (pitch reversed), a
Savitzky-Golay second derivative of the position (`scipy.signal.savgol_filter`, 0.3 s window,
cubic), `R^T (a - g)` by scipy's `Rotation`; both then averaged over the flapping cycle alike
(zero-phase low-pass at 0.4 x the flapping frequency, at most 5 Hz: the `imu` block's own
comparison) on the rows both have. Times: `fwid reconstruct` as a whole process (both flights,
figures off), against the peer in the same run.
"""

from __future__ import annotations

import argparse
import gzip
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _provenance  # noqa: F401  (this checkout's fwid first)
import numpy as np
from _provenance import markdown, provenance
from scipy.signal import savgol_filter
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "realdata"
MAP = ROOT / "docs" / "guide" / "flapper.toml"
FLIGHTS = ("fd_model_tuning_level_flight_1", "fd_model_tuning_wAlt_1")
VEHICLE = {"mass": 0.103, "Ix": 3.2e-4, "Iy": 4.9e-4, "Iz": 3.5e-4, "Ixz": 0.0, "g": 9.81}


def naive(path: Path, signs=(1.0, -1.0, 1.0)):
    """The peer: `(t, specific force (n, 3) FRD, accelerometer (n, 3) FRD m/s^2)`."""
    lines = gzip.open(path, "rt").read().splitlines()
    head = [h.strip() for h in lines[0].split(",")]
    rows = [r.split(",") for r in lines[1:]]
    d = np.array([[float(c) for c in r] for r in rows if len(r) == len(head)])
    c = {h: d[:, i] for i, h in enumerate(head)}
    t = c["timeTick"] * 1e-3
    dt = float(np.median(np.diff(t)))
    Z = np.diag([1.0, -1.0, -1.0])  # z-up, FLU -> NED, FRD
    pos = np.stack([c["otX0"], c["otY0"], c["otZ0"]], 1) @ Z
    ang = np.stack([c["otYaw0"], c["otPitch0"], c["otRoll0"]], 1) * np.array(signs[::-1])
    R = Z @ Rotation.from_euler("ZYX", ang, degrees=True).as_matrix() @ Z
    a = savgol_filter(pos, int(round(0.3 / dt)) | 1, 3, deriv=2, delta=dt, axis=0)
    f = np.einsum("nji,nj->ni", R, a - [0.0, 0.0, VEHICLE["g"]])
    acc = np.stack([c["accX"], -c["accY"], -c["accZ"]], 1) * 9.80665
    return t, f, acc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "realdata.md"))
    args = ap.parse_args(argv)
    if not all((REAL / f"{n}.csv.gz").exists() for n in FLIGHTS):
        print(f"realdata: the real recordings are not beside the repository ({REAL})")
        return 2
    from fwid.reconstruction._imu import agreement

    with tempfile.TemporaryDirectory() as tmp:
        raw = Path(tmp) / "raw"
        raw.mkdir()
        for n in FLIGHTS:
            (raw / f"{n}.csv.gz").symlink_to(REAL / f"{n}.csv.gz")
        (raw / "vehicle.json").write_text(json.dumps(VEHICLE))
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "fwid.cli", "reconstruct", str(raw),
                               "--map", str(MAP), "--out", str(Path(tmp) / "out"),
                               "--no-figures", "--quiet", "--max-dropout", "1.0", "--keep-ground"],
                              capture_output=True, text=True, cwd=ROOT)
        t_fwid = time.perf_counter() - t0
        if proc.returncode != 0:
            print(proc.stdout, proc.stderr)
            return 1
        rep = json.loads((Path(tmp) / "out" / "reconstruction.json").read_text())["flights"]
        rows, t_peer = [], 0.0
        for n, entry in zip(FLIGHTS, rep):
            data = np.genfromtxt(Path(tmp) / "out" / f"{n}.csv", delimiter=",", names=True)
            t = data["t"]
            fpose = np.stack([data[k] for k in "XYZ"], 1) / VEHICLE["mass"]
            acc = {k: data[k] for k in ("acc_x", "acc_y", "acc_z")}
            flap = float(np.nanmedian(data["f"]))
            mine = agreement(t, fpose, None, acc, flap)["acc"]
            s = time.perf_counter()
            tn, fn, an = naive(REAL / f"{n}.csv.gz")
            t_peer += time.perf_counter() - s
            keep = (tn >= t[0] - 1e-6) & (tn <= t[-1] + 1e-6)
            peer = agreement(tn[keep], fn[keep], None,
                             dict(zip(("acc_x", "acc_y", "acc_z"), an[keep].T)), flap)["acc"]
            rows.append((n, entry, mine, peer, float(t[-1] - t[0])))
    prov = provenance()
    out = ["# Real Flapper Drone flights: reconstruction against the onboard accelerometer", "",
           "Cycle-averaged specific force from the pose against the accelerometer (correlation "
           "and rms, m/s^2), fwid and a naive Savitzky-Golay differentiation handed the "
           "convention fwid found. Data: federicoangioni/flappingModel (TU Delft Cyberzoo), "
           "see ../shared/realdata/SOURCES.md.", "",
           "| flight | duration | convention found | fwid corr x / y / z | naive corr x / y / z "
           "| fwid rms x / y / z | naive rms x / y / z |", "|---|---|---|---|---|---|---|"]
    for n, entry, mine, peer, dur in rows:
        fmt = lambda d, k: " / ".join(f"{d[a][k]:.3f}" for a in "xyz")  # noqa: E731
        out.append(f"| {n} | {dur:.1f} s | {entry['imu']['frame']} | {fmt(mine, 'corr')} | "
                   f"{fmt(peer, 'corr')} | {fmt(mine, 'rms')} | {fmt(peer, 'rms')} |")
    out += ["", f"`fwid reconstruct` of both flights, whole process with figures off: "
            f"{t_fwid:.1f} s; the naive peer: {t_peer:.2f} s (reading and differentiation "
            "only, no smoothing, no loads' moments, no checks).", "",
            "Warnings fwid wrote:", ""]
    for n, entry, *_ in rows:
        out += [f"- {n}: " + "; ".join(entry["warnings"])]
    text = markdown("\n".join(out) + "\n", prov)
    Path(args.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
