"""A raw take as read from disk (numpy, no JAX), and the checks every raw form shares:
a uniform time base, unit quaternions, dropouts no longer than a stated limit."""

from __future__ import annotations

import gzip
import io
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._errors import FlightDataError

#: Longest dropout (s) bridged by the smoother unless told otherwise (`max_dropout`).
MAX_DROPOUT = 0.1
#: Largest | |q| - 1 | of a recorded quaternion accepted.
QUAT_TOLERANCE = 1e-3


class OnboardLog(NamedTuple):
    """The autopilot's log: its own clock `t` (s) and its columns (`de dr f p q r`, extras)."""

    path: str
    t: np.ndarray
    columns: dict[str, np.ndarray]


class RawTake(NamedTuple):
    """One raw recording, in north-east-down, before smoothing.

    - `t` (s): the tracking system's time base (uniform, step `dt`);
    - `pos` `(n, 3)` (m) and `quat` `(n, 4)` (body -> NED, Hamilton, scalar first, signs
      made continuous), NaN where the body was lost (`tracked` False);
    - `controls`: `de dr f` and extra columns on `t` (the fwid raw form; a map's take:
      the controls it maps, `acc_x ..` and `p_gyro ..`), else None;
    - `onboard`: the autopilot's log (the Motive form), else None;
    - `dropouts`: `[start, end]` times of the samples lost, one pair per gap.
    """

    name: str
    path: str
    source: str
    frame: str
    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    tracked: np.ndarray
    controls: dict[str, np.ndarray] | None
    onboard: OnboardLog | None
    dropouts: list[list[float]]
    warnings: list[str]
    #: the pose convention used, when onboard sensors checked it (`_imu.Convention`)
    convention: object = None
    #: the tracking's own rate (Hz) when it is slower than the time base's (its poses
    #: repeated on the rows between), else None
    tracking_rate: float | None = None
    #: the airborne stretch of the recording this take was cut to (`_airborne.cut_take`):
    #: `t_s` `[t0, t1]`, `part` (1, 2, ... in time order) `of` how many flights it gives
    stretch: dict | None = None

    @property
    def dt(self) -> float:
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))


def take_name(path) -> str:
    """A take's name: its file name without `.csv` or `.csv.gz` (or `.tsv`, `.mat`, `.npz`,
    `.h5`, `.hdf5`)."""
    name = Path(path).name.removesuffix(".gz")
    for suffix in (".csv", ".tsv", ".mat", ".npz", ".h5", ".hdf5"):
        if name.endswith(suffix):
            return name.removesuffix(suffix)
    return name


def read_lines(path) -> list[str]:
    """The text lines of a recording, plain or gzip-compressed (told by the `.gz` suffix);
    a file that cannot be read is a `FlightDataError` naming it."""
    path = Path(path)
    try:
        if path.suffix == ".gz":
            with gzip.open(path, "rt", encoding="utf-8-sig") as fh:
                return fh.read().splitlines()
        return path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError, EOFError) as e:
        raise FlightDataError(f"{path}: cannot read the file ({e})") from None


def parse_rows(lines: list[str], path: str, first_line: int, width: int | None = None) -> np.ndarray:
    """Comma-separated numbers `(rows, columns)`, empty cells as NaN; a cell that is not a
    number is a `FlightDataError` naming the file, the line and the cell."""
    fast = _parse_fast(lines, width)
    if fast is not None:
        return fast
    rows = []
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        cells = line.rstrip("\r\n").split(",")
        if width is not None:
            cells = (cells + [""] * width)[:width]
        try:
            rows.append([float(c) if c.strip() else np.nan for c in cells])
        except ValueError:
            bad = next(c for c in cells if c.strip() and not _is_number(c))
            raise FlightDataError(f"{path}, line {first_line + i}: {bad.strip()!r} is not a number; "
                                  "every data cell must be a number or empty") from None
    if not rows:
        raise FlightDataError(f"{path}: no data rows after the header")
    n = max(len(r) for r in rows)
    out = np.full((len(rows), n), np.nan)
    for i, r in enumerate(rows):
        out[i, : len(r)] = r
    return out


def _fill_empty(text: str) -> str:
    """Every empty cell of comma-separated `text` written `nan`."""
    text = "\n" + text + "\n"
    for _ in range(2):  # ",,," needs two passes (replacements do not overlap)
        text = text.replace(",,", ",nan,")
    return text.replace("\n,", "\nnan,").replace(",\n", ",nan\n").strip("\n")


def _parse_fast(lines: list[str], width: int | None) -> np.ndarray | None:
    """numpy's C parser on the text with empty cells written `nan`; None where it fails (a
    cell that is not a number, ragged rows: the slow path says where)."""
    text = "\n".join(lines)  # one join in C; blank lines are skipped by numpy's parser
    if "\r" in text:
        text = text.replace("\r", "")
    if not text.strip():
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data = np.loadtxt(io.StringIO(_fill_empty(text)), delimiter=",", ndmin=2)
    except ValueError:
        return None
    if width is not None and data.shape[1] != width:
        if data.shape[1] > width:
            return data[:, :width]
        return None
    return data


def _is_number(c: str) -> bool:
    try:
        float(c)
    except ValueError:
        return False
    return True


def check_time(t: np.ndarray, path: str, first_line: int, what: str = "time") -> float:
    """The step of a uniform, strictly increasing time base `t`; else a `FlightDataError`
    naming the line and time where it is not (tolerance: 1 % of the step)."""
    if len(t) < 3:
        raise FlightDataError(f"{path}: only {len(t)} samples; a take needs at least 3")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise FlightDataError(f"{path}, line {first_line + i}: the {what} cell is empty; "
                              "every row needs its time")
    d = np.diff(t)
    dt = float(np.median(d))
    bad = np.flatnonzero(np.abs(d - dt) > 0.01 * abs(dt) + 1e-9)
    if dt <= 0 or bad.size:
        i = int(bad[0]) if bad.size else 0
        raise FlightDataError(
            f"{path}, line {first_line + i + 1}: the time base is not uniform (step {d[i]:.6g} s "
            f"at t = {t[i + 1]:.6g} s, elsewhere {dt:.6g} s); export every frame (no frame drops), "
            "or resample the take onto a uniform time base")
    return dt


def check_quaternions(q: np.ndarray, tracked: np.ndarray, t: np.ndarray, path: str,
                      first_line: int, tol: float = QUAT_TOLERANCE) -> None:
    """Every tracked quaternion has unit norm within `tol`; else a `FlightDataError` naming
    the line and time of the first that has not."""
    norm = np.linalg.norm(q, axis=1)
    bad = np.flatnonzero(tracked & (np.abs(norm - 1.0) > tol))
    if bad.size:
        i = int(bad[0])
        raise FlightDataError(
            f"{path}, line {first_line + i} (t = {t[i]:.6g} s): the quaternion's norm is "
            f"{norm[i]:.6g}, not 1 (tolerance {tol:g}); export unit quaternions and check the "
            "column order (scalar first: qw qx qy qz)")


def dropouts(t: np.ndarray, tracked: np.ndarray, path: str, max_dropout: float,
             dropped: np.ndarray | None = None) -> list[list[float]]:
    """The `[start, end]` times of each run of lost samples; a run longer than
    `max_dropout` seconds is a `FlightDataError` naming it (and, where `dropped` marks
    samples dropped as glitches or held values, how many of them it holds)."""
    lost = ~tracked
    edges = np.diff(np.concatenate([[0], lost.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    dt = float(np.median(np.diff(t)))
    out = []
    for a, b in zip(starts, ends):
        length = (b - a + 1) * dt
        if length > max_dropout + 1e-9:
            n = 0 if dropped is None else int(np.sum(dropped[a:b + 1]))
            why = (f" ({n} of its {b - a + 1} frames dropped as glitches or held values)"
                   if n else "")
            raise FlightDataError(
                f"{path}: the body is lost for {length:.3g} s from t = {t[a]:.6g} s to "
                f"{t[b]:.6g} s{why}, longer than the {max_dropout:g} s that are bridged; fill the "
                "gap in the tracking software, cut the take, or raise --max-dropout")
        out.append([float(t[a]), float(t[b])])
    return out


def trim_untracked(t, pos, quat, tracked, *others):
    """Cut the lost samples at the start and the end of a take (nothing to bridge there)."""
    idx = np.flatnonzero(tracked)
    if idx.size < 3:
        return None
    s = slice(int(idx[0]), int(idx[-1]) + 1)
    return (t[s], pos[s], quat[s], tracked[s], *[
        None if o is None else {k: v[s] for k, v in o.items()} for o in others])
