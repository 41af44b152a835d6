"""The Vicon Nexus CSV export of a model's segments (`Segments` block) or of Tracker / Nexus
objects (`Objects` block).

The file holds one block per kind of data (`Devices`, `Joints`, `Model Outputs`,
`Segments`, `Trajectories`, ...), each: its name on a line of its own, the frame rate (Hz) on
the next, a row naming each segment (`subject:segment`) above its first column, the column
row `Frame, Sub Frame, RX, RY, RZ, TX, TY, TZ` (six columns a segment), a units row (`deg`,
`mm`), then one row a frame, up to a blank line. Nexus writes a UTF-8 byte-order mark and
CRLF line ends (both are read).

`TX TY TZ` is the segment's origin in the lab (the units row's unit); `RX RY RZ` is Nexus's
default helical angle: the rotation vector (axis times angle, in the units row's unit) that
turns the lab's axes onto the segment's, so `R = exp([r]x)` maps segment axes to lab axes. A
block whose header names Euler angles (`Euler XYZ` ... on its name, column or units row) is
read as intrinsic angles about the segment's X, Y and Z in the order named (default XYZ,
`Rx(RX) Ry(RY) Rz(RZ)`). Vicon's lab frame is z-up (X forward, Y left, Z up: `--frame
z-up`, the default for this form), segment axes alike. Empty cells are frames where the
segment was not tracked.
"""

from __future__ import annotations

import re

import numpy as np

from .._errors import FlightDataError
from ._frames import frame_times
from ._raw import MAX_DROPOUT, RawTake, parse_rows
from ._rotations import euler_to_matrix_ordered, exp_so3, to_ned
from ._tracked import pose_take

#: The names of the blocks a Nexus CSV export may hold.
BLOCKS = ("Devices", "Joints", "Model Outputs", "Segments", "Trajectories", "Objects")
#: The blocks that hold a rigid body's pose.
POSE_BLOCKS = ("Segments", "Objects")
_COLUMNS = ("RX", "RY", "RZ", "TX", "TY", "TZ")
_LENGTH = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
_ANGLE = {"deg": np.pi / 180, "rad": 1.0}
_EXPORT = ("export the trial from Nexus as CSV (Export CSV) with the Segments block ticked "
           "(or Objects from Vicon Tracker)")


def _block_name(line: str) -> str:
    """A block's name (`Segments` of `Segments (Euler XYZ)`)."""
    return line.strip().strip(",").split(" (")[0].strip()


def _block_at(lines: list[str], i: int) -> bool:
    return (_block_name(lines[i]) in BLOCKS and i + 3 < len(lines)
            and lines[i + 3].replace(" ", "").lower().startswith("frame,subframe"))


def is_nexus(lines: list[str]) -> bool:
    """Whether `lines` are a Vicon Nexus CSV export (a block name, the rate, then the
    `Frame, Sub Frame` columns three lines on)."""
    return bool(lines) and _block_at(lines, 0)


def read_nexus(path: str, lines: list[str], body: str | None = None, frame: str = "z-up",
               onboard=None, max_dropout: float = MAX_DROPOUT) -> RawTake:
    """Read a Vicon Nexus CSV export's segment (or object) into a `RawTake` in
    north-east-down.

    **Arguments:**
    - `path`, `lines`: the export and its text lines;
    - `body`: the segment's name, `subject:segment` or the part after the colon (needed when
      the block holds several);
    - `frame`: the export's world frame (`z-up`, Vicon's; `y-up`; `ned`), body axes alike;
    - `onboard`: the autopilot's log (default `NAME.onboard.csv` beside the export);
    - `max_dropout`: the longest gap (s) accepted.
    """
    starts = [i for i in range(len(lines)) if _block_name(lines[i]) in POSE_BLOCKS
              and _block_at(lines, i)]
    if not starts:
        found = [_block_name(ln) for i, ln in enumerate(lines) if _block_at(lines, i)]
        raise FlightDataError(f"{path}: a Vicon Nexus CSV export with no Segments or Objects "
                              f"block (it holds {', '.join(found)}); {_EXPORT}")
    s = starts[0]
    block = _block_name(lines[s])
    try:
        rate = float(lines[s + 1].split(",")[0])
    except ValueError:
        rate = float("nan")
    if not np.isfinite(rate) or rate <= 0:
        raise FlightDataError(f"{path}, line {s + 2}: the {block} block's frame rate "
                              f"{lines[s + 1].strip()!r} is not a number of Hz; {_EXPORT}")
    split = [[c.strip() for c in lines[s + k].split(",")] for k in (2, 3, 4)]
    width = max(len(r) for r in split)
    names, cols, units = ((r + [""] * width)[:width] for r in split)
    segments = {n: j for j, n in enumerate(names) if n}
    if not segments:
        raise FlightDataError(f"{path}, line {s + 3}: the {block} block names no segment; "
                              f"{_EXPORT}")
    body = _pick(path, block, list(segments), body)
    j = segments[body]
    got = [c.upper() for c in cols[j:j + 6]]
    if got != list(_COLUMNS):
        raise FlightDataError(f"{path}, line {s + 4}: segment {body!r} has columns "
                              f"{', '.join(got)}, not RX, RY, RZ, TX, TY, TZ; {_EXPORT}")
    angle, length = (units[j] or "deg").lower(), (units[j + 3] or "mm").lower()
    if angle not in _ANGLE or length not in _LENGTH:
        raise FlightDataError(f"{path}, line {s + 5}: units {units[j]!r}, {units[j + 3]!r} of "
                              f"segment {body!r} unknown (deg or rad; mm, cm or m)")
    header = " ".join(lines[s + k] for k in (0, 2, 3, 4))
    euler = re.search(r"euler\W*([xyz]{3})?", header, re.IGNORECASE)
    order = (euler.group(1) or "XYZ").upper() if euler else None
    end = next((k for k in range(s + 5, len(lines)) if not lines[k].strip(" ,")), len(lines))
    first = s + 6
    data = parse_rows(lines[s + 5:end], path, first, width=width)
    ft = frame_times(data[:, 0], (data[:, 0] - 1) / rate, rate, path, first, max_dropout,
                     what="Frame")  # Nexus counts frames from 1
    full = np.full((len(ft.t), 6), np.nan)
    full[ft.rows] = data[:, j:j + 6]
    rot, pos = full[:, :3] * _ANGLE[angle], full[:, 3:] * _LENGTH[length]
    tracked = np.all(np.isfinite(full), axis=1)
    rot = np.where(tracked[:, None], rot, 0.0)
    R = euler_to_matrix_ordered(rot, order) if order else exp_so3(rot)
    pos, R = to_ned(pos, R, frame)
    kind = f"{order} Euler" if order else "helical"
    return pose_take(path, ft.t, pos, R, tracked, frame, ft.warnings, onboard, max_dropout,
                     f"Vicon Nexus CSV export ({block} {body}, {frame}, {length}, {kind})",
                     f"segment {body!r}")


def _pick(path: str, block: str, names: list[str], body: str | None) -> str:
    """The segment named `body` (whole, or the part after `subject:`), or the only one."""
    if body is None:
        if len(names) > 1:
            raise FlightDataError(f"{path}: the {block} block holds {', '.join(names)}; choose "
                                  "one with --body NAME")
        return names[0]
    hits = [n for n in names if n == body] or [n for n in names if n.split(":")[-1] == body]
    if len(hits) != 1:
        why = "no" if not hits else "more than one"
        raise FlightDataError(f"{path}: {why} segment named {body!r} in the {block} block; it "
                              f"holds {', '.join(names)} (give one with --body NAME)")
    return hits[0]
