"""Which raw form a file is (told by its first lines, or a MATLAB file's own header), and the
raw files of a folder."""

from __future__ import annotations

import os
from pathlib import Path

from .._errors import FlightDataError, InputError
from ._arrays import is_array_file
from ._fwid_raw import read_fwid_raw
from ._map import RecordingMap, read_map
from ._mapped import read_mapped, read_mapped_log
from ._motive import is_old_export, old_export_error, read_motive
from ._qtm import is_qtm_mat, is_qtm_tsv, read_qtm_mat, read_qtm_tsv
from ._raw import MAX_DROPOUT, RawTake, read_lines, take_name
from ._rotations import FRAMES
from ._vicon import is_nexus, read_nexus


#: The files of a folder read as raw takes: CSV (fwid raw, Motive, Vicon Nexus), QTM's TSV
#: and MATLAB exports, gzip-compressed or not; through a recording map, NumPy and HDF5 too.
RAW_PATTERNS = ("*.csv", "*.csv.gz", "*.tsv", "*.tsv.gz", "*.mat")
MAPPED_PATTERNS = RAW_PATTERNS + ("*.npz", "*.h5", "*.hdf5")


def raw_files(paths, recording_map=None) -> list[Path]:
    """The raw takes named by `paths` (files, or folders: their top-level `RAW_PATTERNS` files,
    with a recording map `MAPPED_PATTERNS`, that are no other take's autopilot log or pose file
    (`NAME.onboard.csv`, the map's `[onboard] file` and `[tracking] file`); subfolders are
    ignored), in order."""
    m = recording_map
    if m is not None and not isinstance(m, RecordingMap):
        m = read_map(m)
    out = []
    for p in [paths] if isinstance(paths, (str, os.PathLike)) else paths:
        p = Path(p)
        if p.is_dir():
            found = sorted({f for pat in (RAW_PATTERNS if m is None else MAPPED_PATTERNS)
                            for f in p.glob(pat)
                            if not f.name.endswith((".onboard.csv", ".onboard.csv.gz"))})
            if m is not None:
                side = set().union(*(m.side_files(f) for f in found))
                found = [f for f in found if f not in side]
            if not found:
                kinds = ", ".join(RAW_PATTERNS if m is None else MAPPED_PATTERNS)
                raise FlightDataError(f"{p}: no raw take ({kinds}) in the folder")
            out += found
        elif p.is_file():
            out.append(p)
        else:
            raise FlightDataError(f"{p}: no such file or folder")
    return out


def distinct_names(files) -> None:
    """Refuse, before any work, takes of one name (`a.csv` and `a.mat`, or `x/a.csv` and
    `y/a.csv`): their flights would be written to one file."""
    names: dict[str, Path] = {}
    for f in map(Path, files):
        other = names.setdefault(take_name(f), f)
        if other != f:
            raise InputError(f"{other} and {f}: two takes named {take_name(f)!r} would write one "
                             f"flight ({take_name(f)}.csv); reconstruct them into separate --out "
                             "folders, or rename one")


def read_raw(path, *, body: str | None = None, frame: str | None = None,
             onboard=None, max_dropout: float = MAX_DROPOUT, recording_map=None,
             strict_frame: bool = False) -> RawTake:
    """Read one raw take: a fwid raw CSV, a tracking export, or a lab's file through a map.

    The exports: Motive, Vicon Nexus and Qualisys QTM.
    The take comes back in north-east-down, body axes forward-right-down (the guide's pages
    on raw recordings and on your lab's recordings).

    **Arguments:**
    - `path`: a fwid raw CSV, a Motive CSV export (its first line starts `Format Version`),
      a Vicon Nexus CSV export (a `Segments` or `Objects` block), a Qualisys QTM 6DOF TSV
      (first line `NO_OF_FRAMES`) or MATLAB (`.mat`) export; or, through a map, a lab's CSV,
      TSV, MATLAB (`.mat`), NumPy (`.npz`) or HDF5 file;
    - `body`: the rigid body's (segment's) name (needed when the take holds several);
    - `frame`: `ned`, `y-up` or `z-up`: the recording's world frame, body axes alike
      (default: `ned` for the fwid raw CSV, `y-up` for Motive, `z-up` for Vicon and QTM);
    - `onboard`: the autopilot's log of a tracking system's take (default
      `NAME.onboard.csv` beside it);
    - `max_dropout`: the longest gap in the tracking (s) that is bridged;
    - `recording_map`: a recording map (its path, or [`fwid.reconstruction.read_map`][]'s
      result) for a lab's own columns: the take's pose (or, without `[tracking]`, a Motive
      export's), its autopilot's controls and sensors;
    - `strict_frame`: with a map that names onboard sensors, refuse a pose convention they
      contradict instead of using the one they agree with.

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
    m = recording_map
    if m is not None and not isinstance(m, RecordingMap):
        m = read_map(m)
    if m is not None and m.tracking_file is not None:  # the pose in a file of its own
        return read_mapped(str(path), m, frame=frame, strict_frame=strict_frame,
                           max_dropout=max_dropout)
    if m is None and is_qtm_mat(path):
        return read_qtm_mat(str(path), body=body, frame=frame or "z-up", onboard=onboard,
                            max_dropout=max_dropout)
    if is_array_file(path):
        if m is None or m.position is None:
            raise FlightDataError(f"{path}: an array file is read through a recording map with "
                                  "a [tracking] section (--map MAP.toml); see the guide's page "
                                  "on recordings")
        return read_mapped(str(path), m, frame=frame, strict_frame=strict_frame,
                           max_dropout=max_dropout)
    lines = read_lines(path)
    if not lines:
        raise FlightDataError(f"{path}: empty file")
    if lines[0].startswith("Format Version"):
        take = read_motive(str(path), lines, body=body, frame=frame or "y-up",
                           onboard=False if m is not None else onboard, max_dropout=max_dropout)
        if m is None:
            return take
        log = read_mapped_log(onboard or m.log_path(path), m, path)
        notes = [] if log is not None else [f"no autopilot log ({m.log_path(path).name}): "
                                            "no controls, the pose alone"]
        if m.position is not None:
            notes.append(f"the map's [tracking] is not used: a Motive export holds its own "
                         f"pose (the rigid body's columns)")
        return take._replace(onboard=log, warnings=take.warnings + notes)
    vendor = (read_nexus if is_nexus(lines) else read_qtm_tsv if is_qtm_tsv(lines) else None)
    if vendor is not None:
        if m is not None:
            raise InputError(f"{path}: --map is for a lab's own columns; a "
                             f"{'Vicon Nexus' if vendor is read_nexus else 'Qualisys QTM'} "
                             "export is read as it is (leave --map out)")
        return vendor(str(path), lines, body=body, frame=frame or "z-up", onboard=onboard,
                      max_dropout=max_dropout)
    if m is not None and m.position is not None:
        return read_mapped(str(path), m, frame=frame, strict_frame=strict_frame,
                           max_dropout=max_dropout, lines=lines)
    if m is not None:
        raise FlightDataError(f"{path}: the map {m.path} has no [tracking] section, which only "
                              "a Motive export (first line 'Format Version') may leave out; "
                              "map the pose's columns in [tracking]")
    if is_old_export(lines):
        raise old_export_error(str(path), lines)
    if onboard is not None:
        raise InputError(f"{path}: --onboard is for Motive takes; a fwid raw CSV holds its "
                         "controls itself")
    return read_fwid_raw(str(path), lines, frame=frame or "ned", max_dropout=max_dropout)
