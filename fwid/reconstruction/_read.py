"""Which raw form a file is (told by its first line), and the raw files of a folder."""

from __future__ import annotations

import os
from pathlib import Path

from .._errors import FlightDataError, InputError
from ._fwid_raw import read_fwid_raw
from ._motive import is_old_export, old_export_error, read_motive
from ._raw import MAX_DROPOUT, RawTake, read_lines
from ._rotations import FRAMES


def raw_files(paths) -> list[Path]:
    """The raw takes named by `paths` (files, or folders: their top-level `*.csv` that do not
    end in `.onboard.csv`; subfolders are ignored), in order."""
    out = []
    for p in [paths] if isinstance(paths, (str, os.PathLike)) else paths:
        p = Path(p)
        if p.is_dir():
            found = sorted(f for f in [*p.glob("*.csv"), *p.glob("*.csv.gz")]
                           if not f.name.endswith((".onboard.csv", ".onboard.csv.gz")))
            if not found:
                raise FlightDataError(f"{p}: no raw take (*.csv) in the folder")
            out += found
        elif p.is_file():
            out.append(p)
        else:
            raise FlightDataError(f"{p}: no such file or folder")
    return out


def read_raw(path, *, body: str | None = None, frame: str | None = None,
             onboard=None, max_dropout: float = MAX_DROPOUT) -> RawTake:
    """Read one raw take, either form (the guide's page on recordings), into north-east-down.

    **Arguments:**
    - `path`: a fwid raw CSV or a Motive CSV export (its first line starts `Format Version`);
    - `body`: the Motive rigid body's name (needed when the take holds several);
    - `frame`: `ned`, `y-up` or `z-up`: the recording's world frame, body axes alike
      (default: `ned` for the fwid raw CSV, `y-up` for Motive);
    - `onboard`: the autopilot's log of a Motive take (default `NAME.onboard.csv` beside it);
    - `max_dropout`: the longest gap in the tracking (s) that is bridged.

    **Returns:** a `fwid.reconstruction.RawTake`. Raises a [`fwid.FlightDataError`][]
    naming the file, the line or time and the fix for every input that cannot be used.
    """
    if frame is not None and frame not in FRAMES:
        raise InputError(f"frame {frame!r} unknown; use one of {', '.join(FRAMES)}")
    if max_dropout <= 0:
        raise InputError(f"max_dropout must be positive seconds, got {max_dropout!r}")
    path = Path(path)
    if not path.is_file():
        raise FlightDataError(f"{path}: no such file")
    lines = read_lines(path)
    if not lines:
        raise FlightDataError(f"{path}: empty file")
    if lines[0].startswith("Format Version"):
        return read_motive(str(path), lines, body=body, frame=frame or "y-up",
                           onboard=onboard, max_dropout=max_dropout)
    if is_old_export(lines):
        raise old_export_error(str(path), lines)
    if onboard is not None:
        raise InputError(f"{path}: --onboard is for Motive takes; a fwid raw CSV holds its "
                         "controls itself")
    return read_fwid_raw(str(path), lines, frame=frame or "ned", max_dropout=max_dropout)
