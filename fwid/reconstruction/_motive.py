"""The OptiTrack Motive CSV export (the guide's page on recordings) and the autopilot's log
beside it.

Line 1 holds the take's settings as key/value pairs (`Format Version`, `Capture Frame Rate`,
`Export Frame Rate`, `Rotation Type`, `Length Units`, ...), line 2 is empty, lines 3-7 name each
data column (type, name, ID, Rotation/Position, component), data rows follow: `Frame`,
`Time (Seconds)`, then the columns. The rigid body is picked by name; its `Rotation` (X Y Z W
quaternion, or X Y Z Euler angles in degrees in the header's rotation order) and `Position`
X Y Z columns are read, empty cells are dropouts. The time base comes from the frame numbers
(`_frames`), the length unit from the header or the numbers (`_units`); glitches are dropped
(`_glitches`).

Motive's Euler angles (Motive 1.6 on; NaturalPoint's knowledge-base article "Changes in
Motive's reported Euler angles"): right-handed, in degrees, X, Y and Z the angles about the
rigid body's X, Y and Z axes, applied as relative (intrinsic) rotations in the order the
header names: order `XYZ` is `Rx(X) Ry(Y) Rz(Z)`.
"""

from __future__ import annotations

import numpy as np

from .._errors import FlightDataError
from ._frames import frame_times
from ._raw import MAX_DROPOUT, RawTake, check_quaternions, check_time, parse_rows
from ._rotations import euler_to_matrix_ordered, to_ned, tracked_matrices
from ._tracked import pose_take
from ._units import length_unit
from ._wings import wing_frequency

#: The rotation orders of Motive's Euler exports.
EULER_ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")
#: The oldest `Format Version` of the layout read here (Motive 1.7 on: 1.2, 1.21, 1.22, 1.23).
FORMAT_VERSION = 1.2
_FIRST_DATA_LINE = 8
_REEXPORT = ("re-export the take from Motive 1.7 or later (2.x, 3.x) as CSV with the default "
             "layout (header information on)")


def settings(line: str) -> dict[str, str]:
    """The key/value pairs of a Motive export's first line."""
    cells = [c.strip() for c in line.rstrip("\r\n").split(",")]
    return {cells[i]: cells[i + 1] for i in range(0, len(cells) - 1, 2)}


def is_old_export(lines: list[str]) -> bool:
    """Whether `lines` are an OptiTrack export in the old 1.1-era layout (Arena, Tracking
    Tools, Motive up to 1.5): `comment,...`, `info,version,...` and `frame,...` lines."""
    head = [ln.split(",", 1)[0].strip().lower() for ln in lines[:12]]
    branded = head[:1] == ["comment"] and "optitrack" in lines[0].lower()
    return branded or (head[:1] in (["comment"], ["info"]) and "info" in head)


def old_export_error(path: str, lines: list[str]) -> FlightDataError:
    """The one-line refusal of an export in the old layout."""
    version = next((ln.split(",")[2].strip() for ln in lines[:12]
                    if ln.lower().startswith("info,version,") and ln.count(",") >= 2), "1.1")
    return FlightDataError(f"{path}: an OptiTrack CSV export in the old layout (format version "
                           f"{version}: 'info' and 'frame' lines), which fwid does not read; "
                           f"{_REEXPORT}")


def _check_layout(path: str, lines: list[str], head: dict[str, str]) -> None:
    """The export is in the layout read here: format version 1.2 or later and the five lines
    that name each column."""
    version = _number(head.get("Format Version"))
    if version is not None and version < FORMAT_VERSION - 1e-9:
        raise FlightDataError(f"{path}: Motive CSV Format Version {version:g}, an older layout "
                              f"than fwid reads (1.2 or later); {_REEXPORT}")
    if len(lines) < _FIRST_DATA_LINE:
        raise FlightDataError(f"{path}: the Motive header is cut short (7 header lines expected)")
    second = [(lines[i].split(",") + ["", ""])[1].strip() for i in (2, 3)]
    first = lines[6].split(",", 1)[0].strip()
    # Some exports (format 1.22 with Euler angles among them) leave the first two cells of
    # the descriptor rows blank: the rows are read by their place, lines 3-7, all the same.
    if second == ["", ""] and "Rigid Body" not in [c.strip() for c in lines[2].split(",")]:
        second = ["no column types"]
    if second not in (["Type", "Name"], ["", ""]) or first != "Frame":
        raise FlightDataError(
            f"{path}: lines 3-7 of the Motive export do not name the columns (Type, Name, ID, "
            f"Rotation/Position, then Frame, Time (Seconds), X, Y, ...); {_REEXPORT}")


def _time_base(head, comp, data, path, max_dropout):
    """`(data on the time base, t, warnings)`: one row per frame from the `Frame` column at
    the export's frame rate (missing frames: rows of NaN), else the time column (uniform)."""
    rate = _number(head.get("Export Frame Rate")) or _number(head.get("Capture Frame Rate"))
    if comp[0] == "Frame" and rate:
        ft = frame_times(data[:, 0], data[:, 1], rate, path, _FIRST_DATA_LINE, max_dropout)
        full = np.full((len(ft.t), data.shape[1]), np.nan)
        full[ft.rows] = data
        return full, ft.t, ft.warnings
    t = data[:, 1]
    dt = check_time(t, path, _FIRST_DATA_LINE, "Time (Seconds)")
    warnings = []
    if rate and abs(rate * dt - 1) > 0.01:
        warnings.append(f"the header's frame rate {rate:g} Hz differs from the time column's "
                        f"{1 / dt:.6g} Hz; the time column is used")
    return data, t, warnings


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
    _check_layout(path, lines, head)
    rot = head.get("Rotation Type", "Quaternion")
    euler = rot.upper() if rot.upper() in EULER_ORDERS else None
    if euler is None and rot.lower() != "quaternion":
        raise FlightDataError(f"{path}: Rotation Type {rot!r} unknown; re-export the take from "
                              "Motive with Rotation Type = Quaternion")
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
    angles = "XYZ" if euler else "XYZW"
    need = [("Rotation", c) for c in angles] + [("Position", c) for c in "XYZ"]
    lost = [f"{g} {c}" for g, c in need if (g, c) not in where]
    if lost:
        what = f"{euler} Euler angles" if euler else "a quaternion"
        raise FlightDataError(f"{path}: rigid body {body!r} has no {', '.join(lost)} column(s); "
                              f"export its rotation ({what}, as the header says) and its position")
    data = parse_rows(lines[7:], path, _FIRST_DATA_LINE, width=width)
    data, t, warnings = _time_base(head, comp, data, path, max_dropout)
    rot = np.stack([data[:, where[("Rotation", c)]] for c in angles], 1)
    pos = np.stack([data[:, where[("Position", c)]] for c in "XYZ"], 1)
    scale, units, said = length_unit(head.get("Length Units"), pos, path)
    warnings += said
    pos = pos * scale
    tracked = np.all(np.isfinite(rot), axis=1) & np.all(np.isfinite(pos), axis=1)
    R = _matrices(rot, tracked, euler, t, path)
    pos, R = to_ned(pos, R, frame)
    flap = _wings(data, t, kind, names, group, comp, body, euler, frame, R, tracked, path)
    if flap is not None:
        warnings.append(flap[1])
    rotation = f"{euler} Euler" if euler else "quaternion"
    return pose_take(path, t, pos, R, tracked, frame, warnings, onboard, max_dropout,
                     f"Motive CSV export (body {body}, {frame}, {units}, {rotation})",
                     f"rigid body {body!r}", None if flap is None else {"f": flap[0]})


def _matrices(rot, tracked, euler, t, path):
    """Body -> world matrices of a rigid body's rotation columns (a quaternion X Y Z W, or
    Euler angles in degrees in the header's order), the identity where it is not tracked."""
    if euler:
        return euler_to_matrix_ordered(np.deg2rad(np.where(tracked[:, None], rot, 0.0)), euler)
    q = rot[:, [3, 0, 1, 2]]
    check_quaternions(q, tracked, t, path, _FIRST_DATA_LINE)
    return tracked_matrices(q, tracked)


def _wings(data, t, kind, names, group, comp, body, euler, frame, R, tracked, path):
    """The flapping frequency from the take's wing rigid bodies (`_wings`), or None."""
    angles = "XYZ" if euler else "XYZW"
    wings = {}
    for w in dict.fromkeys(n for k, n in zip(kind, names) if k == "Rigid Body" and n):
        if w == body or "wing" not in w.lower():
            continue
        cols = {c.upper(): i for i, (k, n, g, c) in enumerate(zip(kind, names, group, comp))
                if k == "Rigid Body" and n == w and g == "Rotation"}
        if not all(c in cols for c in angles):
            continue
        rot = np.stack([data[:, cols[c]] for c in angles], 1)
        ok = np.all(np.isfinite(rot), axis=1)
        if ok.sum() < 3:
            continue
        _, Rw = to_ned(np.zeros((len(t), 3)), _matrices(rot, ok, euler, t, path), frame)
        wings[w] = (Rw, ok)
    if not wings:
        return None
    f, note = wing_frequency(t, R, tracked, wings)
    return None if f is None else (f, note)


def _number(text) -> float | None:
    try:
        return float(text)
    except (TypeError, ValueError):
        return None
