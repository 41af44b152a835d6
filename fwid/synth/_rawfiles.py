"""Write raw recordings (`simulate_raw`) as files (the raw-recording formats): the fwid raw CSV; an
OptiTrack Motive CSV export, a Vicon Nexus CSV export, a QTM 6DOF TSV or MATLAB export, each
with its autopilot log; or a lab's MATLAB log with its recording map; and beside them the truth
(`truth/NAME.csv`, `truth/vehicle.json`, `truth/NAME.json`)."""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import numpy as np

from ._delfly import DELFLY
from ._labmat import LAB_MAP, write_lab_mat
from ._raw import RAW_AMPLITUDE, quat_mul, simulate_raw
from ._simulate import COLUMNS
from ._vendors import write_nexus, write_qtm_mat, write_qtm_tsv
from ._write import INPUT_CYCLE

#: Raw forms `fwid simulate --raw` writes.
RAW_FORMS = ("fwid", "motive", "vicon", "qtm", "qtm-mat", "matlab")

#: The forms written with an autopilot log `NAME.onboard.csv` on its own clock, and the
#: suffix of each form's take.
WITH_LOG = ("motive", "vicon", "qtm", "qtm-mat")
SUFFIX = {"fwid": ".csv", "motive": ".csv", "vicon": ".csv", "qtm": ".tsv", "qtm-mat": ".mat",
          "matlab": ".mat"}

#: The recording map written beside the `matlab` form's logs.
MAP_NAME = "lab.toml"

#: NED from Motive's y-up world (and body) axes: `x_ned = C X_motive` (x = X, y = Z, z = -Y).
Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

#: Columns of the fwid raw CSV.
RAW_COLUMNS = ("t", "x", "y", "z", "qw", "qx", "qy", "qz", "de", "dr", "f")

#: Where the static second rigid body of a Motive take stands (y-up, mm) and its markers'
#: offset from the DelFly's pivot (body axes, mm).
WAND_POSITION = (850.0, 20.0, -1200.0)
MARKER_OFFSET = (30.0, 0.0, -8.0)

_TRUTH_EXTRA = ("x", "y", "z", "qw", "qx", "qy", "qz")


def _write_text(path: Path, text: str) -> Path:
    """Write `text` to `path` atomically (a temporary file renamed into place)."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)
    return path


def _table(cols, fmt) -> str:
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack(cols), delimiter=",", fmt=fmt)
    return buf.getvalue().replace("nan", "")


def ned_to_y_up(position, quat) -> tuple[np.ndarray, np.ndarray]:
    """Motive's y-up position and quaternion `[W X Y Z]` of a NED position and body -> NED
    quaternion: `X_motive = C^T x_ned`, `R_motive = C^T R_ned C` (so the vector part turns
    with `C^T` too)."""
    position = np.asarray(position, float)
    quat = np.asarray(quat, float)
    vec = quat[..., 1:] @ Y_UP  # rows: C^T v
    return position @ Y_UP, np.concatenate([quat[..., :1], vec], axis=-1)


def write_fwid_raw(path, raw: dict, flips: float = 0.05, seed: int = 0) -> Path:
    """The fwid raw CSV of a `simulate_raw` result: `RAW_COLUMNS`, NED, quaternion signs
    flipped on a random share `flips` of the frames (runs and single frames), empty pose
    cells where tracking lost the body."""
    take = raw["take"]
    n = take["t"].size
    rng = np.random.default_rng(seed)
    flip = rng.random(n) < flips / 2  # single frames
    for start in rng.integers(0, n, max(1, round(flips / 2 * n / 27))):  # runs of 5-50 frames
        flip[start : start + rng.integers(5, 51)] = True
    sign = np.where(flip, -1.0, 1.0)
    quat = take["quat"] * sign[:, None]
    cols = [take["t"], *take["position"].T, *quat.T, take["de"], take["dr"], take["f"]]
    text = ",".join(RAW_COLUMNS) + "\n" + _table(cols, "%.10g")
    return _write_text(Path(path), text)


def _motive_header(name: str, rate: float, n: int, bodies) -> str:
    """Lines 1-7 of a Motive CSV export: the key/value line, an empty line, the Type, Name,
    ID and group lines (one entry per data column) and the axis line."""
    head = (f"Format Version,1.23,Take Name,{name},Take Notes,,Capture Frame Rate,{rate:.6f},"
            f"Export Frame Rate,{rate:.6f},Capture Start Time,2026-11-25 04.01.02.123 PM,"
            f"Capture Start Frame,0,Total Frames in Take,{n},Total Exported Frames,{n},"
            "Rotation Type,Quaternion,Length Units,Millimeters,Coordinate Space,Global")
    types, names, ids, groups, axes = [], [], [], [], []
    for kind, bname, bid, parts in bodies:
        for group, letters in parts:
            for a in letters:
                types.append(kind)
                names.append(bname)
                ids.append(bid)
                groups.append(group)
                axes.append(a)
    rows = [",Type," + ",".join(types), ",Name," + ",".join(names), ",ID," + ",".join(ids),
            ",," + ",".join(groups), "Frame,Time (Seconds)," + ",".join(axes)]
    return head + "\n\n" + "\n".join(rows) + "\n"


def write_motive(path, raw: dict, body: str = "DelFly") -> Path:
    """The Motive CSV export of a `simulate_raw` take: y-up millimetres, the rigid body `body`
    (rotation X Y Z W, position X Y Z, mean marker error), a static second rigid body `Wand`,
    and one of `body`'s markers (`Rigid Body Marker` columns), empty where tracking lost it."""
    take = raw["take"]
    t = take["t"]
    n = t.size
    rate = 1.0 / (t[1] - t[0])
    pos, quat = ned_to_y_up(take["position"], take["quat"])
    pos = pos * 1000.0
    rng = np.random.default_rng(n)
    lost = raw["lost"]
    err = np.where(lost, np.nan, rng.uniform(0.08, 0.3, n))
    # a marker of the body (offset in body axes, mm), y-up
    marker = pos + (_matrices(raw["truth"]) @ np.asarray(MARKER_OFFSET)) @ Y_UP
    marker = marker + 0.2 * rng.standard_normal((n, 3))
    marker[lost] = np.nan
    wand_q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))  # X Y Z W: identity
    wand_p = np.asarray(WAND_POSITION) + 0.05 * rng.standard_normal((n, 3))
    wand_e = rng.uniform(0.05, 0.15, n)
    rot = ("Rotation", "XYZW")
    rigid = [rot, ("Position", "XYZ"), ("Mean Marker Error", [""])]
    bodies = [("Rigid Body", body, "1", rigid), ("Rigid Body", "Wand", "2", rigid),
              ("Rigid Body Marker", f"{body}:Marker1", "1", [("Position", "XYZ")])]
    head = _motive_header(Path(path).stem, rate, n, bodies)
    qxyzw = np.column_stack([quat[:, 1:], quat[:, :1]])
    cols = [np.arange(n), t, *qxyzw.T, *pos.T, err, *wand_q.T, *wand_p.T, wand_e, *marker.T]
    fmt = ["%d", "%.6f"] + ["%.9f"] * 4 + ["%.6f"] * 4 + ["%.9f"] * 4 + ["%.6f"] * 4 + ["%.6f"] * 3
    return _write_text(Path(path), head + _table(cols, fmt))


def _matrices(truth) -> np.ndarray:
    return _quat_matrices(np.column_stack([truth[c] for c in ("qw", "qx", "qy", "qz")]))


def write_onboard(path, raw: dict) -> Path:
    """The autopilot log `NAME.onboard.csv`: `t,de,dr,f,p,q,r` on the autopilot's clock."""
    ob = raw["onboard"]
    names = ("t", "de", "dr", "f", "p", "q", "r")
    text = ",".join(names) + "\n" + _table([ob[c] for c in names], ["%.9f"] + ["%.10g"] * 6)
    return _write_text(Path(path), text)


def write_truth(out_dir, name: str, raw: dict, vehicle=DELFLY) -> Path:
    """`truth/NAME.csv` (section-1 columns, exact, plus the pose), `truth/NAME.json` (trim,
    first input, the simulation's truth incl. the clock offset, gyro bias and dropouts) and
    `truth/vehicle.json`."""
    d = Path(out_dir) / "truth"
    d.mkdir(parents=True, exist_ok=True)
    names = list(COLUMNS) + list(_TRUTH_EXTRA)
    text = ",".join(names) + "\n" + _table([raw["truth"][c] for c in names], "%.17g")
    path = _write_text(d / f"{name}.csv", text)
    _write_text(d / f"{name}.json", json.dumps(raw["meta"], indent=2) + "\n")
    _write_text(d / "vehicle.json", json.dumps(vehicle.vehicle(), indent=2) + "\n")
    return path


def write_take(path, raw: dict, form: str, seed: int = 0) -> Path:
    """Write the take of a `simulate_raw` result in the raw form `form` (`RAW_FORMS`); the
    vendors' exports hold the pose alone (the rigid body `DelFly` beside a still `Wand`)."""
    take = raw["take"]
    if form == "fwid":
        return write_fwid_raw(path, raw, seed=seed)
    if form == "motive":
        return write_motive(path, raw)
    tracked = ~raw["lost"]
    q = np.where(tracked[:, None], take["quat"], [1.0, 0.0, 0.0, 0.0])
    pose = (take["t"], take["position"], _quat_matrices(q), tracked)
    if form == "vicon":
        return write_nexus(path, *pose)
    if form == "qtm":
        return write_qtm_tsv(path, *pose)
    if form == "qtm-mat":
        return write_qtm_mat(path, *pose)
    return write_lab_mat(path, *pose, {c: take[c] for c in ("de", "dr", "f")})


def _quat_matrices(q) -> np.ndarray:
    from ._sixdof import quat_to_matrix

    return np.asarray(quat_to_matrix(np.asarray(q, float)))


def write_raw_flights(out_dir, raw: str = "fwid", n_flights: int = 4, axis: str = "lon",
                      seed: int = 0, prefix: str | None = None, **kw) -> list[Path]:
    """Simulate `n_flights` 6-DOF flights (`simulate_raw`) and write them in the raw form
    `raw` (`RAW_FORMS`) into `out_dir`, with `vehicle.json` and the truth under `truth/`:
    `"fwid"`: `NAME.csv`, the fwid raw CSV; `"motive"`, `"vicon"`: `NAME.csv`, an OptiTrack Motive
    or a Vicon Nexus CSV export; `"qtm"`: `NAME.tsv`, `"qtm-mat"`: `NAME.mat`, a QTM 6DOF TSV or
    MATLAB export; each export with the autopilot log `NAME.onboard.csv` on its own clock;
    `"matlab"`: `NAME.mat`, a lab's MATLAB log of the pose and PWM outputs on one clock, read
    through the recording map `lab.toml` written beside it (`fwid reconstruct OUT --map
    OUT/lab.toml`).

    Flight `i` draws from `numpy.random.default_rng(seed + i)` as `write_flights` does: the
    input cycles through `INPUT_CYCLE`, the amplitude is `RAW_AMPLITUDE[axis] x U(0.8, 1.25)`,
    the quiet start `U(0.8, 1.3)` s; `kw` (e.g. `duration`, `rate`, `position_noise`,
    `attitude_noise`, `dropouts`, `onboard_rate`, `clock_offset`, `effect`) applies to all.

    **Returns:** the raw take paths, in order.
    """
    if raw not in RAW_FORMS:
        raise ValueError(f"raw form must be one of {RAW_FORMS}, got {raw!r}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    vehicle = kw.get("vehicle", DELFLY)
    _write_text(out / "vehicle.json", json.dumps(vehicle.vehicle(), indent=2) + "\n")
    stem = axis if prefix is None else prefix
    paths = []
    for i in range(n_flights):
        rng = np.random.default_rng(seed + i)
        args = {"input": INPUT_CYCLE[i % len(INPUT_CYCLE)],
                "amplitude": RAW_AMPLITUDE[axis] * rng.uniform(0.8, 1.25),
                "start": rng.uniform(0.8, 1.3)}
        sim_seed = int(rng.integers(2**31 - 1))
        args.update(kw)
        rec = simulate_raw(axis=axis, seed=sim_seed, onboard=raw in WITH_LOG, **args)
        name = f"{stem}_{i}"
        paths.append(write_take(out / f"{name}{SUFFIX[raw]}", rec, raw, seed=sim_seed))
        if raw in WITH_LOG:
            write_onboard(out / f"{name}.onboard.csv", rec)
        write_truth(out, name, rec, vehicle)
    if raw == "matlab":
        _write_text(out / MAP_NAME, LAB_MAP)
    return paths
