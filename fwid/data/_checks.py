"""Checks on a flight's time histories, run by [`fwid.data.load_flight`][].

Each check raises a [`fwid.FlightDataError`][] with one line that names the file, says what
is wrong and where, and how to fix it, e.g.

`lon_0.csv: column 'q' has NaN at lines 19, 20 (t=0.085 s); fill or cut these samples`

Read from a file, places are given as the lines an editor shows (1-based, the header line
counted: the first sample under a one-line header is line 2); called directly on arrays, as
0-based sample indices ("row 0" is the first sample).

The strict checks apply to the columns of the flight-data format (`KNOWN_COLUMNS`) and to the
columns a model requires; other (extra) columns are kept as they are and never used by fwid.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

import numpy as np
from jaxtyping import Float

if TYPE_CHECKING:  # jaxtyping's ArrayLike imports JAX, which reading a file needs not
    from jaxtyping import ArrayLike

from .._errors import FlightDataError
from ._timebase import JITTER, time_quantum

#: The columns of the flight-data format.
KNOWN_COLUMNS = (
    "t", "q", "u", "w", "theta", "p", "r", "v", "phi", "psi",
    "de", "dr", "f", "X", "Y", "Z", "L", "M", "N",
)  # fmt: skip

#: A flight needs at least this many samples ...
MIN_SAMPLES = 50
#: ... and at least this duration [s] to be fitted.
MIN_DURATION = 1.0

#: Read as seconds, the time base of a flight has a step of at most `MAX_STEP` [s], lasts at
#: most `MAX_DURATION` [s], and samples at least once per `MAX_BEATS_PER_STEP` wing beats
#: (see `check_time_unit`); else its unit is one of `TIME_UNITS` (its factor to seconds).
MAX_STEP = 0.5
MAX_DURATION = 3600.0
MAX_BEATS_PER_STEP = 2.5
TIME_UNITS = {"ms": 1e3, "us": 1e6, "ns": 1e9}
_UNIT_WORDS = {"ms": "milliseconds", "us": "microseconds", "ns": "nanoseconds"}

#: Largest plausible magnitude in radians (or rad/s) of angle-like columns; beyond it the
#: column looks like degrees (or deg/s). Pitch and roll are bounded by pi; the heading by
#: 2 pi (an unwrapped heading can exceed it: the message says what to do then); rates by
#: 35 rad/s (2000 deg/s, far beyond any body rate of a flapping-wing MAV); control
#: deflections by 1 rad (57 deg, beyond any tail deflection).
DEGREE_LIMITS = {
    "theta": np.pi,
    "phi": np.pi,
    "psi": 2 * np.pi,
    "p": 35.0,
    "q": 35.0,
    "r": 35.0,
    "de": 1.0,
    "dr": 1.0,
}

_MAX_ROWS_LISTED = 5


def _rows(idx: np.ndarray, lines=None) -> str:
    """`row 3` / `rows 3, 4, 5` / `rows 3, 4, 5, 6, 7 and 12 more` (0-based samples); with
    `lines` (each sample's line in the file), `line 5` / `lines 5, 6, 7` instead."""
    idx = np.asarray(idx)
    word = "row" if lines is None else "line"
    at = idx if lines is None else np.asarray(lines)[idx]
    shown = ", ".join(str(int(i)) for i in at[:_MAX_ROWS_LISTED])
    more = idx.size - _MAX_ROWS_LISTED
    rows = (f"{word} " if idx.size == 1 else f"{word}s ") + shown
    return rows + (f" and {more} more" if more > 0 else "")


def _row(i: int, lines=None) -> str:
    """One place: `row i`, or `line L` with `lines`."""
    return _rows(np.array([i]), lines)


def _at(t: np.ndarray | None, i: int) -> str:
    if t is None or i >= t.shape[0] or not np.isfinite(t[i]):
        return ""
    return f" (t={t[i]:.6g} s)"


def _g(x: float) -> str:
    return f"{x:.4g}"


def check_columns(name: str, names: Iterable[str], require: Iterable[str] = ()) -> None:
    """The time column `t` and every column in `require` are present."""
    names = list(names)
    has = ", ".join(names) if names else "none"
    if "t" not in names:
        alias = [c for c in names if c.strip().lower() in ("time", "t", "time_s", "t_s", "t [s]")]
        fix = f"rename '{alias[0]}' to 't'" if alias else "add a time column 't' in seconds"
        raise FlightDataError(f"{name}: missing time column 't' (columns: {has}); {fix}")
    missing = [c for c in dict.fromkeys(require) if c not in names]
    if missing:
        s, it = ("s", "them") if len(missing) > 1 else ("", "it")
        cols = ", ".join(repr(c) for c in missing)
        raise FlightDataError(
            f"{name}: missing column{s} {cols} needed by this model (columns: {has}); "
            f"add {it} or choose a model that does not need {it}"
        )


def _what(x: np.ndarray) -> str:
    nan = np.isnan(x)
    return "NaN" if nan.all() else ("infinite values" if not nan.any() else "NaN/infinite values")


def check_finite(name: str, col: str, x: Float[ArrayLike, " n"], t=None, lines=None) -> None:
    """`x` has no NaN (or empty cells) and no infinities. `lines`: each sample's line in
    the file, for the message (default: 0-based rows)."""
    check_all_finite(name, {col: x}, t, lines)


def check_all_finite(name: str, columns: Mapping[str, ArrayLike], t=None, lines=None) -> None:
    """No column of `columns` has NaN (or empty cells) or infinities; the message names
    every bad column at once, with its rows (or `lines`)."""
    bad = {}
    for col, x in columns.items():
        x = np.asarray(x, dtype=float)
        idx = np.flatnonzero(~np.isfinite(x))
        if idx.size:
            bad[col] = (idx, _what(x[idx]))
    if not bad:
        return
    t = None if t is None else np.asarray(t, dtype=float)
    if len(bad) == 1:
        (col, (idx, what)), = bad.items()
        raise FlightDataError(
            f"{name}: column '{col}' has {what} at {_rows(idx, lines)}{_at(t, int(idx[0]))}; "
            "fill or cut these samples"
        )
    what = {w for _, w in bad.values()}
    what = what.pop() if len(what) == 1 else "NaN/infinite values"
    where = ", ".join(f"'{c}' ({_rows(idx, lines)})" for c, (idx, _) in bad.items())
    raise FlightDataError(f"{name}: columns {where} have {what}; fill or cut these samples")


def check_time(name: str, t: Float[ArrayLike, " n"], lines=None) -> float:
    """`t` is strictly increasing with a uniform step, up to jitter; returns the typical
    (median) step [s]. `lines`: each sample's line in the file, for the message (default:
    0-based rows).

    Steps within 0.1 % of the median step (`UNIFORM_RTOL`), or within the rounding of the
    printed time stamps, are uniform. Steps that jitter further, up to 25 % of the step
    (`JITTER`), are accepted: the loader resamples such a flight onto the uniform grid,
    with a warning (`fwid.data._timebase.uniform_flight`). A step further off (a gap of
    missing samples, a logger's pause) is refused.
    """
    t = np.asarray(t, dtype=float)
    if t.shape[0] < 2:
        return float("nan")
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        how = "repeats" if d[i - 1] == 0 else "goes back to"
        raise FlightDataError(
            f"{name}: t is not strictly increasing at {_row(i, lines)}: t {how} {t[i]:.6g} s "
            f"after {t[i - 1]:.6g} s ({_row(i - 1, lines)}); sort the rows by time and remove "
            "duplicates"
        )
    dt = float(np.median(d))
    bad = np.flatnonzero(np.abs(d - dt) > JITTER * dt)
    if bad.size:
        j = int(bad[0])
        hint = ""
        quantum = time_quantum(t)
        if quantum > JITTER * dt:
            hint = " (t is rounded to {:g} s: write it with more decimals)".format(quantum)
        raise FlightDataError(
            f"{name}: t is not uniformly sampled: the step from {_row(j, lines)} to "
            f"{j + 1 if lines is None else lines[j + 1]} "
            f"(t={t[j]:.6g} s) is {_g(d[j])} s but the typical step is {_g(dt)} s "
            f"({bad.size} step{'s' if bad.size > 1 else ''} off by more than "
            f"{JITTER:.0%}, the jitter fwid resamples){hint}; resample the flight onto a "
            "uniform time grid, or split it into flights at a gap"
        )
    return dt


def check_time_unit(name: str, t: Float[ArrayLike, " n"], f=None) -> None:
    """`t` is in seconds, not milliseconds, microseconds or nanoseconds.

    Read as seconds, the time base of a flight must sample the flight: a step of at most
    `MAX_STEP` (0.5 s), a duration of at most `MAX_DURATION` (an hour, beyond any
    flapping-wing flight on one battery), and, with the flapping frequency `f` [Hz], at
    most `MAX_BEATS_PER_STEP` wing beats between two samples (`f` below five times the
    Nyquist frequency). A time base that fails any of these is refused, naming the unit
    (of `TIME_UNITS`) that would make it a flight's.
    """
    t = np.asarray(t, dtype=float)
    if t.shape[0] < 2:
        return
    dt = float(np.median(np.diff(t)))
    if not dt > 0:
        return  # not increasing: check_time says so
    span = float(t[-1] - t[0])
    beats = None if f is None or np.size(f) == 0 else float(np.median(np.asarray(f, float)))

    def fits(scale: float) -> bool:
        step = dt / scale
        return (step <= MAX_STEP and span / scale <= MAX_DURATION
                and (beats is None or beats * step <= MAX_BEATS_PER_STEP))

    if fits(1.0):
        return
    unit = next((u for u, k in TIME_UNITS.items() if fits(k) and dt / k >= 1e-5), None)
    seen = f"read as seconds, its step is {_g(dt)} s ({_g(1 / dt)} Hz) over {_g(span)} s"
    if beats is not None and beats * dt > MAX_BEATS_PER_STEP:
        seen += (f", and the wings (f = {_g(beats)} Hz) would beat {beats * dt:.3g} times "
                 "between two samples")
    if unit is None:
        raise FlightDataError(f"{name}: t does not look like seconds: {seen}; give t in "
                              "seconds (fwid expects seconds)")
    raise FlightDataError(f"{name}: t looks like {_UNIT_WORDS[unit]}, not seconds: {seen}; "
                          f"divide t by {TIME_UNITS[unit]:.0f} (fwid expects seconds)")


def check_length(name: str, t: Float[ArrayLike, " n"]) -> None:
    """At least `MIN_SAMPLES` samples over at least `MIN_DURATION` seconds."""
    t = np.asarray(t, dtype=float)
    n = t.shape[0]
    duration = float(t[-1] - t[0]) if n else 0.0
    if n < MIN_SAMPLES or duration < MIN_DURATION * (1 - 1e-9):
        raise FlightDataError(
            f"{name}: flight too short to fit: {n} sample{'s' if n != 1 else ''} over "
            f"{duration:.3g} s; need at least {MIN_SAMPLES} samples and {MIN_DURATION:g} s "
            "of data (use a longer recording)"
        )


def check_units(name: str, columns: Mapping[str, ArrayLike], t: ArrayLike | None = None) -> None:
    """Angles, rates and deflections are in radians, not degrees (see `DEGREE_LIMITS`); every
    column that looks like degrees is named in the one message (with `t`, the time the values
    leave the plausible range when they start plausible, as radians that diverged do)."""
    found = []
    for col, limit in DEGREE_LIMITS.items():
        if col not in columns:
            continue
        x = np.asarray(columns[col], dtype=float)
        if x.size == 0:
            continue
        over = np.abs(x) > limit * (1 + 1e-6)
        if over.any():
            found.append((col, float(np.max(np.abs(x))), limit, int(np.argmax(over))))
    if not found:
        return
    fix = "multiply by pi/180"
    if any(col == "psi" for col, _, _, _ in found):
        fix += " (or, for an unwrapped heading in radians, subtract a multiple of 2*pi)"
    if len(found) == 1:
        col, m, limit, _ = found[0]
        rate = col in ("p", "q", "r")
        raise FlightDataError(
            f"{name}: column '{col}' looks like {'deg/s' if rate else 'degrees'} "
            f"(max |{col}| = {m:.4g}, above the {limit:.3g} {'rad/s' if rate else 'rad'} "
            f"plausible); fwid expects {'rad/s' if rate else 'radians'}: {fix}"
            + _left_range(columns, found, t)
        )
    cols = ", ".join(f"'{c}' (max {m:.4g}, plausible {lim:.3g})" for c, m, lim, _ in found)
    raise FlightDataError(f"{name}: columns {cols} look like degrees or deg/s; fwid expects "
                          f"radians and rad/s: {fix} in each" + _left_range(columns, found, t))


def _left_range(columns: Mapping[str, ArrayLike], found: list, t: ArrayLike | None) -> str:
    """When the implausible values start only after a plausible first tenth of the flight, the
    columns may be radians of a flight that tumbled or a simulation that diverged: say when."""
    x = np.asarray(columns[found[0][0]], dtype=float)
    first = min(k for _, _, _, k in found)
    if first < max(1, x.size // 10):
        return ""
    when = (f"t = {float(np.asarray(t, dtype=float)[first]):.4g} s" if t is not None
            else f"sample {first}")
    return (f"; or, if they are radians, the flight leaves the plausible range at {when} (a "
            "vehicle that tumbled or a simulation that diverged): keep the part before it")


def check_frequency(name: str, f: Float[ArrayLike, " n"], t=None, lines=None) -> None:
    """The flapping frequency `f` [Hz] is positive and finite."""
    f = np.asarray(f, dtype=float)
    check_finite(name, "f", f, t, lines)
    idx = np.flatnonzero(f <= 0)
    if idx.size:
        t = None if t is None else np.asarray(t, dtype=float)
        raise FlightDataError(
            f"{name}: column 'f' (flapping frequency, Hz) must be positive but is "
            f"{_g(f[idx[0]])} at {_rows(idx, lines)}{_at(t, int(idx[0]))}; "
            "fix or cut these samples"
        )


def check_flight(
    name: str,
    t: Float[ArrayLike, " n"],
    columns: Mapping[str, ArrayLike],
    require: Iterable[str] = (),
    lines=None,
) -> float:
    """Every check, in order: columns present, finite values, time in seconds, time grid,
    length, units, flapping frequency. `columns` holds every column but `t`.

    **Arguments:**
    - `name`: the file name, used in the messages.
    - `t`: time [s].
    - `columns`: the other columns by name.
    - `require`: columns the caller needs.
    - `lines`: each sample's line in the file (1-based, as an editor shows it), for the
      messages; default: 0-based rows.

    **Returns:** the time step [s].

    Raises a [`fwid.FlightDataError`][] at the first problem found.
    """
    require = tuple(require)
    check_columns(name, ["t", *columns], require)
    t = np.asarray(t, dtype=float)
    check_finite(name, "t", t, None, lines)
    strict = [c for c in columns if c in KNOWN_COLUMNS or c in require]
    check_all_finite(name, {c: columns[c] for c in strict}, t, lines)
    check_time_unit(name, t, columns.get("f"))
    dt = check_time(name, t, lines)
    check_length(name, t)
    check_units(name, {c: columns[c] for c in strict}, t)
    if "f" in columns:
        check_frequency(name, columns["f"], t, lines)
    return dt
