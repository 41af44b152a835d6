"""The fwid raw CSV (the guide's page on recordings): `t,x,y,z,qw,qx,qy,qz,de,dr,f` (+ extra
columns, kept), empty pose cells where the tracking lost the body, one file holding both
sources; glitches dropped (`_glitches`)."""

from __future__ import annotations

import numpy as np

from .._errors import FlightDataError
from ._glitches import drop_glitches
from ._raw import (
    MAX_DROPOUT, RawTake, check_quaternions, check_time, dropouts, parse_rows, take_name,
    trim_untracked,
)
from ._rotations import continuous_sign, matrix_to_quat, quat_to_matrix, to_ned

POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")
CONTROLS = ("de", "dr", "f")
_EULER = ("phi", "theta", "psi", "roll", "pitch", "yaw")


def read_fwid_raw(path: str, lines: list[str], frame: str = "ned",
                  max_dropout: float = MAX_DROPOUT, name: str | None = None) -> RawTake:
    """Read a fwid raw CSV (its `lines`) into a `RawTake` in north-east-down.

    **Arguments:**
    - `path`: the file (for messages); `lines`: its text lines;
    - `frame`: the Earth frame of the file (`ned`, `y-up`, `z-up`), body axes alike;
    - `max_dropout`: the longest gap (s) accepted.
    """
    header = [h.strip() for h in lines[0].rstrip("\r\n").split(",")]
    missing = [c for c in ("t", *POSE, *CONTROLS) if c not in header]
    if missing:
        euler = [c for c in header if c.lower() in _EULER]
        if euler and any(c.startswith("q") for c in missing):
            raise FlightDataError(
                f"{path}: attitude given as Euler angles ({', '.join(euler)}); read the file "
                "through a recording map that names its columns, units and Euler order "
                "(--map MAP.toml, the guide's page 'Your lab's recordings'), or export the "
                "quaternion qw qx qy qz (body -> Earth, scalar first)")
        raise FlightDataError(f"{path}: missing column(s) {', '.join(missing)}; a fwid raw CSV "
                              "has t,x,y,z,qw,qx,qy,qz,de,dr,f (the guide's page on raw "
                              "recordings); a file with columns of its own is read through a "
                              "recording map (--map MAP.toml, the guide's page 'Your lab's "
                              "recordings')")
    data = parse_rows(lines[1:], path, 2, width=len(header))
    col = {h: data[:, i] for i, h in enumerate(header) if h}
    t = col["t"]
    check_time(t, path, 2)
    pose = np.stack([col[c] for c in POSE], 1)
    tracked = np.all(np.isfinite(pose), axis=1)
    for c in CONTROLS:
        bad = np.flatnonzero(~np.isfinite(col[c]))
        if bad.size:
            raise FlightDataError(f"{path}, line {bad[0] + 2}: column {c} is empty; de dr f are "
                                  "needed on every row")
    q = pose[:, 3:]
    check_quaternions(q, tracked, t, path, 2)
    q = np.where(tracked[:, None], q / np.linalg.norm(np.where(tracked[:, None], q, 1.0), axis=1,
                                                      keepdims=True), np.nan)
    pos = pose[:, :3]
    if frame != "ned":
        R = quat_to_matrix(np.where(tracked[:, None], q, [1.0, 0, 0, 0]))
        pos, R = to_ned(pos, R, frame)
        q = np.where(tracked[:, None], matrix_to_quat(R), np.nan)
    q = continuous_sign(q, tracked)
    kept, warnings = drop_glitches(t, q, tracked, pos, path)
    extras = {h: v for h, v in col.items() if h not in ("t", *POSE)}
    cut = trim_untracked(t, pos, q, kept, extras, {"dropped": tracked & ~kept})
    if cut is None:
        raise FlightDataError(f"{path}: the body is tracked on fewer than 3 rows")
    t, pos, q, tracked, extras, dropped = cut
    gaps = dropouts(t, tracked, path, max_dropout, dropped["dropped"])
    stem = name or take_name(path)
    return RawTake(stem, path, f"fwid raw CSV ({frame})", frame, t, pos, q, tracked, extras,
                   None, gaps, warnings)



