"""Qualisys Track Manager's 6DOF exports: the TSV file and the MATLAB file.

**TSV** (File > Export > To TSV, 6D data): a header block of `KEY<TAB>value` lines
(`NO_OF_FRAMES`, `FREQUENCY`, `BODY_NAMES` ...), then the column row `Frame, Time,
<body> X, Y, Z, Roll, Pitch, Yaw, Residual, Rot[0] .. Rot[8]` for each body (an empty column
between bodies), one tab-separated row a frame. Positions are in mm, angles in degrees; a
body lost in a frame leaves its cells empty; a trimmed export starts at a later frame number.

**MATLAB** (File > Export > To MAT): a struct with `FrameRate`, `Frames`, `StartFrame` and
`RigidBodies` (`Name`, `Positions` bodies x 3 x N in mm, `Rotations` bodies x 9 x N, `RPYs`,
`Residual`), NaN where a body was lost.

The attitude is read from the rotation matrix `Rot[0..8]` (`Rotations`), not the Euler
angles (whose definition is a per-project QTM setting). QTM writes the matrix **column by
column**: `Rot[0..2]` is its first column (r11, r21, r31), `Rot[3..5]` the second, `Rot[6..8]`
the third, so that MATLAB's `reshape(Rotations(1,:,k), 3, 3)` (column-major) gives the matrix,
as QTM's MATLAB export documentation uses it. The matrix maps body (local) axes to the
lab's: its columns are the body's axes in lab coordinates. A reader with the order swapped
would read every attitude inverted; tests write QTM's layout from a known attitude. The
export's own Euler angles check the order (`_order`): where they follow QTM's standard
definition (R = Rx(roll) Ry(pitch) Rz(yaw)) and agree with the matrix read row by row but
not column by column, the matrix is read row by row, with a warning. QTM's
lab frame is z-up by default (`--frame z-up`), body axes alike (x forward, z up).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import FlightDataError
from ._frames import frame_times
from ._raw import MAX_DROPOUT, RawTake, parse_rows
from ._rotations import to_ned
from ._tracked import pose_take

_COMPONENTS = ("X", "Y", "Z", "Roll", "Pitch", "Yaw", "Residual",
               *(f"Rot[{k}]" for k in range(9)))
_EXPORT = ("export the measurement from QTM with File > Export > To TSV, 6D data ticked (or "
           "To MAT)")
_MAT_MAGIC = b"MATLAB 5.0 MAT-file"


def is_qtm_tsv(lines: list[str]) -> bool:
    """Whether `lines` are a QTM TSV export (first line `NO_OF_FRAMES<TAB>...`)."""
    return bool(lines) and lines[0].split("\t", 1)[0].strip() == "NO_OF_FRAMES"


def is_qtm_mat(path) -> bool:
    """Whether `path` is a MATLAB v5 file (told by its first bytes)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(_MAT_MAGIC)) == _MAT_MAGIC
    except OSError:
        return False


#: Median angle (deg) between the export's Euler angles and its matrix within which the two
#: agree (the export rounds both; a wrong order or another Euler definition is tens of deg).
AGREE_DEG = 1.0


def _matrices(rot, tracked, by_rows: bool = False):
    """Body -> lab matrices of QTM's `Rot[0..8]` (column by column, or `by_rows`), identity
    where lost."""
    rot = np.where(tracked[:, None], rot, np.eye(3).ravel()).reshape(-1, 3, 3)
    return rot if by_rows else rot.transpose(0, 2, 1)


def _order(rot, rpy, tracked) -> tuple[bool, str | None]:
    """Whether `Rot[0..8]` is to be read row by row, and the warning when it is: the
    export's Euler angles `rpy` (deg) in QTM's standard definition agree with the matrix
    read row by row and not with it read column by column (QTM's documented order). Where
    the angles agree with neither (a project's own Euler definition), the documented order."""
    from scipy.spatial.transform import Rotation

    ok = tracked & np.all(np.isfinite(rpy), 1)
    if ok.sum() < 3:
        return False, None
    E = Rotation.from_euler("XYZ", rpy[ok], degrees=True)

    def off(by_rows):
        M = _matrices(rot[ok], np.ones(int(ok.sum()), bool), by_rows)
        U, _, Vt = np.linalg.svd(M)
        return float(np.median(np.rad2deg((E.inv() * Rotation.from_matrix(U @ Vt)).magnitude())))

    cols, rows = off(False), off(True)
    if cols > AGREE_DEG and rows <= AGREE_DEG:
        return True, (f"the rotation matrix Rot[0..8] is read row by row: the export's Roll, "
                      f"Pitch, Yaw agree with it so (median {rows:.2g} deg apart) and not "
                      f"column by column, QTM's documented order ({cols:.3g} deg apart)")
    return False, None


def read_qtm_tsv(path: str, lines: list[str], body: str | None = None, frame: str = "z-up",
                 onboard=None, max_dropout: float = MAX_DROPOUT) -> RawTake:
    """Read a QTM 6DOF TSV export's rigid body into a `RawTake` in north-east-down
    (arguments as `read_nexus`)."""
    head, k = {}, 0
    while k < len(lines) and not lines[k].startswith("Frame\t"):
        cells = lines[k].rstrip("\r\n").split("\t")
        if cells[0].strip():
            head[cells[0].strip()] = [c.strip() for c in cells[1:]]
        k += 1
    if k == len(lines):
        raise FlightDataError(f"{path}: a QTM TSV export with no column row (Frame, Time, "
                              f"<body> X ...): not a 6D export; {_EXPORT}")
    try:
        rate = float(head["FREQUENCY"][0])
    except (KeyError, IndexError, ValueError):
        raise FlightDataError(f"{path}: the QTM header has no FREQUENCY line (the frame rate "
                              f"in Hz); {_EXPORT}") from None
    cols = [c.strip() for c in lines[k].rstrip("\r\n").split("\t")]
    names = [n for n in head.get("BODY_NAMES", []) if n] or [
        c[:-2] for c in cols if c.endswith(" X") and c != "X"]
    if not names:
        raise FlightDataError(f"{path}: the QTM export names no rigid body (BODY_NAMES); "
                              f"{_EXPORT}")
    body = _pick(path, names, body)
    j = cols.index(f"{body} X") if f"{body} X" in cols else None
    got = [] if j is None else [c.removeprefix(f"{body} ") for c in cols[j:j + 16]]
    if got != list(_COMPONENTS):
        raise FlightDataError(f"{path}, line {k + 1}: body {body!r} lacks the columns X, Y, Z, "
                              f"Roll, Pitch, Yaw, Residual, Rot[0]..Rot[8]; {_EXPORT}")
    first = k + 2
    data = parse_rows([ln.replace("\t", ",") for ln in lines[k + 1:]], path, first,
                      width=len(cols))
    ft = frame_times(data[:, 0], data[:, 1], rate, path, first, max_dropout, what="Time")
    full = np.full((len(ft.t), 16), np.nan)
    full[ft.rows] = data[:, j:j + 16]
    return _take(path, ft.t, full[:, :3], full[:, 7:], body, frame, ft.warnings, onboard,
                 max_dropout, "QTM 6DOF TSV export", full[:, 3:6])


def read_qtm_mat(path: str, body: str | None = None, frame: str = "z-up", onboard=None,
                 max_dropout: float = MAX_DROPOUT) -> RawTake:
    """Read a QTM MATLAB export's rigid body into a `RawTake` in north-east-down (arguments
    as `read_nexus`)."""
    from scipy.io import loadmat

    try:
        mat = loadmat(path, squeeze_me=True, struct_as_record=False)
    except Exception as e:  # scipy raises several kinds on a damaged file
        raise FlightDataError(f"{path}: cannot read the MATLAB file ({e})") from None
    found = [v for k, v in mat.items() if not k.startswith("__")
             and hasattr(v, "_fieldnames") and "RigidBodies" in v._fieldnames]
    if not found:
        raise FlightDataError(f"{path}: a MATLAB file with no QTM measurement (a struct with "
                              f"FrameRate and RigidBodies); {_EXPORT}")
    m = found[0]
    rb = m.RigidBodies
    names = [str(n) for n in np.atleast_1d(rb.Name)]
    body = _pick(path, names, body)
    i = names.index(body)
    n = int(m.Frames)
    pos = np.asarray(rb.Positions, float).reshape(len(names), 3, n)[i].T
    rot = np.asarray(rb.Rotations, float).reshape(len(names), 9, n)[i].T
    rpy = (np.asarray(rb.RPYs, float).reshape(len(names), 3, n)[i].T
           if hasattr(rb, "RPYs") else np.full((n, 3), np.nan))
    start = int(getattr(m, "StartFrame", 1))
    t = (start - 1 + np.arange(n)) / float(m.FrameRate)
    return _take(path, t, pos, rot, body, frame, [], onboard, max_dropout, "QTM MATLAB export",
                 rpy)


def _take(path, t, pos_mm, rot, body, frame, warnings, onboard, max_dropout, form, rpy):
    tracked = np.all(np.isfinite(pos_mm), axis=1) & np.all(np.isfinite(rot), axis=1)
    by_rows, note = _order(rot, rpy, tracked)
    warnings = list(warnings) + ([note] if note else [])
    pos, R = to_ned(pos_mm * 1e-3, _matrices(rot, tracked, by_rows), frame)
    return pose_take(path, t, pos, R, tracked, frame, warnings, onboard, max_dropout,
                     f"{form} (body {body}, {frame}, mm, rotation matrix)", f"body {body!r}")


def _pick(path: str, names: list[str], body: str | None) -> str:
    if body is None:
        if len(names) > 1:
            raise FlightDataError(f"{path}: the export holds rigid bodies {', '.join(names)}; "
                                  "choose one with --body NAME")
        return names[0]
    if body not in names:
        raise FlightDataError(f"{path}: no rigid body named {body!r} in the export; it holds "
                              f"{', '.join(names)} (give one with --body NAME)")
    return body
