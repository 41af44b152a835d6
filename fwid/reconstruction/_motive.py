"""The OptiTrack Motive CSV export (CONTRACTS section 5b) and the autopilot's log beside it.

Line 1 holds the take's settings as key/value pairs (`Capture Frame Rate`, `Rotation Type`,
`Length Units`, ...), line 2 is empty, lines 3-7 name each data column (type, name, ID,
Rotation/Position, component), data rows follow. The rigid body is picked by name; its
`Rotation` X Y Z W and `Position` X Y Z columns are read, empty cells are dropouts.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import FlightDataError
from ._raw import (
    MAX_DROPOUT, OnboardLog, RawTake, check_quaternions, check_time, dropouts, parse_rows,
    read_lines, take_name, trim_untracked,
)
from ._rotations import continuous_sign, matrix_to_quat, quat_to_matrix, to_ned

UNITS = {"millimeters": 1e-3, "centimeters": 1e-2, "meters": 1.0}
LOG_COLUMNS = ("t", "de", "dr", "f", "p", "q", "r")
_FIRST_DATA_LINE = 8


def settings(line: str) -> dict[str, str]:
    """The key/value pairs of a Motive export's first line."""
    cells = [c.strip() for c in line.rstrip("\r\n").split(",")]
    return {cells[i]: cells[i + 1] for i in range(0, len(cells) - 1, 2)}


def read_motive(path: str, lines: list[str], body: str | None = None, frame: str = "y-up",
                onboard: str | None = None, max_dropout: float = MAX_DROPOUT) -> RawTake:
    """Read a Motive CSV export and its autopilot log into a `RawTake` in
    north-east-down.

    **Arguments:**
    - `path`, `lines`: the take and its text lines;
    - `body`: the rigid body's name (needed when the take holds several);
    - `frame`: the take's world frame (`y-up`, Motive's; `z-up`; `ned`), body axes alike;
    - `onboard`: the autopilot's log; default `NAME.onboard.csv` beside the take, where
      a take without one is tracking only (no controls); `False`: read no log;
    - `max_dropout`: the longest gap (s) accepted.
    """
    head = settings(lines[0])
    rot = head.get("Rotation Type", "Quaternion")
    if rot.lower() != "quaternion":
        raise FlightDataError(
            f"{path}: rotations exported as {rot} Euler angles; re-export the take from Motive "
            "with Rotation Type = Quaternion")
    units = head.get("Length Units", "Meters")
    if units.lower() not in UNITS:
        raise FlightDataError(f"{path}: Length Units {units!r} unknown; re-export in Millimeters "
                              "or Meters")
    if len(lines) < _FIRST_DATA_LINE:
        raise FlightDataError(f"{path}: the Motive header is cut short (7 header lines expected)")
    rows = [[c.strip() for c in lines[i].rstrip("\r\n").split(",")] for i in range(2, 7)]
    width = max(len(r) for r in rows)
    kind, names, _, group, comp = ((r + [""] * width)[:width] for r in rows)
    bodies = list(dict.fromkeys(n for k, n in zip(kind, names) if k == "Rigid Body" and n))
    if not bodies:
        raise FlightDataError(f"{path}: no rigid body in the take (line 3 has no 'Rigid Body' "
                              "column); export the rigid body's data")
    if body is None:
        if len(bodies) > 1:
            raise FlightDataError(f"{path}: the take holds rigid bodies {', '.join(bodies)}; "
                                  "choose one with --body NAME")
        body = bodies[0]
    if body not in bodies:
        raise FlightDataError(f"{path}: no rigid body named {body!r} in the take; it holds "
                              f"{', '.join(bodies)} (give one with --body NAME)")
    where = {}
    for i in range(width):
        if kind[i] == "Rigid Body" and names[i] == body and group[i] in ("Rotation", "Position"):
            where.setdefault((group[i], comp[i].upper()), i)
    need = [("Rotation", c) for c in "XYZW"] + [("Position", c) for c in "XYZ"]
    lost = [f"{g} {c}" for g, c in need if (g, c) not in where]
    if lost:
        raise FlightDataError(f"{path}: rigid body {body!r} has no {', '.join(lost)} column(s); "
                              "export its rotation as a quaternion and its position")
    data = parse_rows(lines[7:], path, _FIRST_DATA_LINE, width=width)
    t = data[:, 1]
    check_time(t, path, _FIRST_DATA_LINE, "Time (Seconds)")
    rate = _number(head.get("Export Frame Rate", head.get("Capture Frame Rate")))
    warnings = []
    dt = float(np.median(np.diff(t)))
    if rate and abs(rate * dt - 1) > 0.01:
        warnings.append(f"the header's frame rate {rate:g} Hz differs from the time column's "
                        f"{1 / dt:.6g} Hz; the time column is used")
    qxyzw = np.stack([data[:, where[("Rotation", c)]] for c in "XYZW"], 1)
    q = qxyzw[:, [3, 0, 1, 2]]
    pos = np.stack([data[:, where[("Position", c)]] for c in "XYZ"], 1) * UNITS[units.lower()]
    tracked = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(pos), axis=1)
    check_quaternions(q, tracked, t, path, _FIRST_DATA_LINE)
    safe = np.where(tracked[:, None], q, [1.0, 0, 0, 0])
    pos, R = to_ned(pos, quat_to_matrix(safe / np.linalg.norm(safe, axis=1, keepdims=True)), frame)
    q = continuous_sign(np.where(tracked[:, None], matrix_to_quat(R), np.nan), tracked)
    cut = trim_untracked(t, pos, q, tracked)
    if cut is None:
        raise FlightDataError(f"{path}: rigid body {body!r} is tracked on fewer than 3 rows")
    t, pos, q, tracked = cut
    gaps = dropouts(t, tracked, path, max_dropout)
    name = take_name(path)
    if onboard is False:
        log = None
    else:
        log = read_onboard(onboard or Path(path).with_name(f"{name}.onboard.csv"), path,
                           given=onboard is not None)
        if log is None:
            warnings.append(f"no autopilot log ({name}.onboard.csv) beside the take: the pose "
                            "alone, no controls")
    return RawTake(name, path, f"Motive CSV export (body {body}, {frame}, {units})", frame, t,
                   pos, q, tracked, None, log, gaps, warnings)


def read_onboard(path, take: str, given: bool = False) -> OnboardLog | None:
    """The autopilot's log `t,de,dr,f,p,q,r` (+ extras) of a take, or None when there is
    none beside the take (a tracking-only take); a log named with `given` that is not
    there, a missing column or a non-uniform clock is a `FlightDataError` naming the
    file."""
    path = Path(path)
    if not path.is_file():
        if given:
            raise FlightDataError(f"{take}: no such autopilot log {path} (--onboard); give the "
                                  "path of the take's log, or leave --onboard out for the pose "
                                  "alone")
        return None
    lines = read_lines(path)
    if not lines:
        raise FlightDataError(f"{path}: empty autopilot log")
    header = [h.strip() for h in lines[0].split(",")]
    missing = [c for c in LOG_COLUMNS if c not in header]
    if missing:
        raise FlightDataError(f"{path}: the autopilot log lacks column(s) {', '.join(missing)}; "
                              f"it needs {','.join(LOG_COLUMNS)}")
    data = parse_rows(lines[1:], str(path), 2, width=len(header))
    cols = {h: data[:, i] for i, h in enumerate(header) if h}
    check_time(cols["t"], str(path), 2)
    for c in LOG_COLUMNS[1:]:
        bad = np.flatnonzero(~np.isfinite(cols[c]))
        if bad.size:
            raise FlightDataError(f"{path}, line {bad[0] + 2}: column {c} is empty; the log "
                                  "needs every cell")
    return OnboardLog(str(path), cols.pop("t"), cols)


def _number(text) -> float | None:
    try:
        return float(text)
    except (TypeError, ValueError):
        return None
