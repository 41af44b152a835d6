"""A lab's own recording read through its recording map (`_map.py`) into a `RawTake`.

The take is a CSV (or tab-separated) file with one header row, or an array file (MATLAB,
NumPy, HDF5: `_arrays.py`). Rows that repeat a time stamp are merged. Its time base is made
uniform (`fwid.data._timebase`), its pose turned into north-east-down with body axes
forward-right-down; the autopilot's columns (in the take itself, or in a log of its own on its own clock) give the controls
through the map's affine maps and the onboard sensors in body axes and SI units. When the
map names an accelerometer or a gyro in the take's own file, the pose's convention is
checked against them (`_imu.choose_convention`) before anything is smoothed. A tracking
stream slower than the log (many rows repeating the previous pose exactly) is taken at its
fresh poses only, interpolated onto the log's rows (`_slow_tracking`).
A Motive export (a map without `[tracking]`) keeps Motive's reader for the pose.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import FlightDataError
from ..data._checks import check_time_unit
from ._arrays import is_array_file, read_arrays
from ._glitches import drop_glitches, held_frames
from ._imu import G0, SENSOR_TO_FRD, Convention, check_scales, choose_convention
from ._map import TIME_UNITS, RecordingMap
from ._raw import (
    MAX_DROPOUT, OnboardLog, RawTake, check_quaternions, dropouts, parse_rows, read_lines,
    take_name, trim_untracked,
)
from ._rotations import (
    continuous_sign, euler_to_matrix_ordered, matrix_to_quat, to_ned, tracked_matrices,
)
from ..data._timebase import onto_grid, uniform_time

#: The share of tracked rows repeating the previous pose beyond which the tracking is taken
#: to run slower than the log (a tracking system drops far fewer frames than this).
SLOW_TRACKING = 0.2


def read_table(path, lines: list[str] | None = None):
    """A CSV file with one header row: `(columns, warnings)`, `columns` a dict of arrays
    (empty cells NaN). A last line cut short (a log stopped mid-write) is dropped with a
    warning. A `.tsv` file (gzip too) is split at tabs."""
    lines = read_lines(path) if lines is None else lines
    if not lines:
        raise FlightDataError(f"{path}: empty file")
    if str(path).lower().removesuffix(".gz").endswith(".tsv"):
        lines = [ln.replace("\t", ",") for ln in lines]
    header = [h.strip() for h in lines[0].rstrip("\r\n").split(",")]
    body = [ln for ln in lines[1:] if ln.strip()]
    notes = []
    if body and len(body[-1].split(",")) < len(header):
        body = body[:-1]
        notes.append("the last line is cut short; dropped")
    data = parse_rows(body, str(path), 2, width=len(header))
    return {h: data[:, i] for i, h in enumerate(header) if h}, notes


def read_columns(path, m: RecordingMap, take: bool = True, lines: list[str] | None = None):
    """The columns the map `m` reads from a take (`take`) or from its autopilot's own log:
    `(columns, warnings)`, from a CSV table or an array file (`_arrays.read_arrays`)."""
    if not is_array_file(path):
        return read_table(path, lines)
    time = m.time_named() if take else ("[onboard] time", m.log_time)
    try:
        return read_arrays(path, m.named(take), time)
    except FlightDataError as e:
        raise FlightDataError(f"{e} (map {m.path})") from None


def _merge_repeated_times(cols: dict, t: np.ndarray, path):
    """Rows that repeat the previous row's time stamp merged (the first kept), with a
    warning: `(cols, t, warnings)`."""
    again = np.concatenate([[False], np.diff(t) == 0])
    if not again.any():
        return cols, t, []
    keep = ~again
    note = (f"{int(again.sum())} row(s) repeat the previous row's time stamp (first at "
            f"t = {t[np.argmax(again)]:.6g} s): merged, the first row of each kept")
    return {k: v[keep] for k, v in cols.items()}, t[keep], [note]


def _slow_tracking(t, quat, pos, seen, path, rate_log):
    """A tracking stream slower than the log: `(held, rate, warnings)`, `held` the rows that
    repeat the previous pose exactly and `rate` (Hz) the fresh poses' rate, when more than
    `SLOW_TRACKING` of the tracked rows are held; else `(None, None, [])`."""
    held = held_frames(quat, pos, seen)
    if held.sum() <= SLOW_TRACKING * max(int(seen.sum()), 1):
        return None, None, []
    fresh = np.flatnonzero(seen & ~held)
    rate = (len(fresh) - 1) / float(t[fresh[-1]] - t[fresh[0]])
    note = (f"the tracking runs at about {rate:.3g} Hz, slower than the log's {rate_log:.3g} Hz "
            f"({int(held.sum())} of {int(seen.sum())} rows repeat the previous pose): the pose "
            "is taken at its fresh samples and interpolated onto the log's rows; the controls "
            "and onboard signals keep the log's rate")
    return held, rate, [note]


def _fill_held(t, pos, att, tracked, held, m: RecordingMap):
    """The recorded positions and attitude columns on the held rows between tracked ones,
    interpolated in time from the tracked rows (Euler angles unwrapped, quaternions' signs
    made continuous first); and `tracked` with those rows added."""
    idx = np.flatnonzero(tracked)
    rows = np.arange(len(t))
    inside = held & ~tracked & (rows > idx[0]) & (rows < idx[-1])
    src = att[idx].astype(float)
    if m.euler is not None:
        src = np.unwrap(src * m.angle_scale, axis=0) / m.angle_scale
    elif m.quaternion is not None:
        src = continuous_sign(src)
    pos, att = pos.astype(float), att.astype(float)
    for a, known in ((pos, pos[idx]), (att, src)):
        for i in range(a.shape[1]):
            a[inside, i] = np.interp(t[inside], t[idx], known[:, i])
    return pos, att, tracked | inside


def _pick(cols: dict, names, path, m: RecordingMap) -> np.ndarray:
    missing = [c for c in names if c not in cols]
    if missing:
        import difflib

        near = {c: difflib.get_close_matches(c, list(cols), n=1) for c in missing}
        said = ", ".join(f"{c!r}" + (f" (did you mean {near[c][0]!r}?)" if near[c] else "")
                         for c in missing)
        raise FlightDataError(f"{path}: no column {said}, which the map {m.path} names (the "
                              f"file has {', '.join(cols)}); fix the map")
    return np.stack([cols[c] for c in names], -1)


def _time(cols, path, m: RecordingMap, column, scale):
    """The time stamps (s) of a table, from a time column or frame numbers at a rate."""
    if column is None and m.frame_column is not None:
        return _pick(cols, [m.frame_column], path, m)[:, 0] / m.frame_rate
    return _pick(cols, [column], path, m)[:, 0] * scale


def _check_time_unit(t, path, m: RecordingMap) -> None:
    """Refuse a time base that is not a flight's in seconds under the map's `[time] unit`,
    naming the unit that makes it one (`fwid.data`'s rule)."""
    if m.time_column is None or _is_seconds(t):
        return
    raw = t / m.time_scale
    fits = [u for u, k in TIME_UNITS.items() if _is_seconds(raw * k)]
    now = next(u for u, k in TIME_UNITS.items() if k == m.time_scale)
    fix = (f"set [time] unit = \"{fits[0]}\" in {m.path}" if fits else
           f"check [time] column and unit in {m.path}")
    step = float(np.median(np.diff(t)))
    raise FlightDataError(f"{path}: with [time] unit = \"{now}\" the samples are {step:.3g} s "
                          f"apart over {t[-1] - t[0]:.3g} s, not a flight's time base; {fix}")


#: The fastest sample rate a recording is taken to have (Hz): tracking systems and autopilot
#: logs run at most a few kHz.
MAX_RATE = 1e4


def _is_seconds(t) -> bool:
    """Whether the time stamps `t`, read as seconds, are a flight's (`fwid.data`'s rule, and
    no faster than `MAX_RATE`)."""
    if len(t) > 1 and float(np.median(np.diff(t))) < 1.0 / MAX_RATE:
        return False
    try:
        check_time_unit("", t)
    except FlightDataError:
        return False
    return True


def mapped_controls(cols, path, m: RecordingMap, g: float = G0) -> dict[str, np.ndarray]:
    """The section-1 controls the map gives (`de dr f`, affine maps of column means) and
    the onboard sensors in body axes (forward-right-down) and SI units: `acc_x acc_y acc_z`
    (m/s^2, specific force) and `p_gyro q_gyro r_gyro` (rad/s)."""
    out = {}
    for k, ctl in m.inputs.items():
        out[k] = ctl.scale * (np.mean(_pick(cols, ctl.columns, path, m), -1) - ctl.offset)
    axes = SENSOR_TO_FRD[m.axes]
    if m.acc is not None:
        a = _pick(cols, m.acc, path, m) * (g if m.acc_scale is None else m.acc_scale) * axes
        out.update(zip(("acc_x", "acc_y", "acc_z"), a.T))
    if m.gyro is not None:
        w = _pick(cols, m.gyro, path, m) * m.gyro_scale * axes
        out.update(zip(("p_gyro", "q_gyro", "r_gyro"), w.T))
    return out


def _check_radians(att, path, m: RecordingMap) -> None:
    """Euler angles said to be in radians whose roll or pitch goes beyond pi (no attitude
    has one) are degrees: refused, naming the map's key."""
    rp = np.abs(att[:, :2])
    rp = rp[np.isfinite(rp)]
    if rp.size and np.mean(rp > np.pi + 1e-6) > 0.001:
        raise FlightDataError(f"{path}: the roll and pitch reach {np.max(rp):.4g} with the map's "
                              f"attitude_unit = \"rad\", beyond pi: they look like degrees; "
                              f"set attitude_unit = \"deg\" in [tracking] of {m.path}")


def _attitude_matrices(att, m: RecordingMap, path):
    """Body -> world matrices of the recorded attitude columns (NaN rows stay NaN-free: the
    identity, masked by `tracked`), and the rows that hold a usable attitude."""
    ok = np.all(np.isfinite(att), 1)
    if m.attitude_form == "matrix":
        M = np.where(ok[:, None], att, np.eye(3).ravel()).reshape(-1, 3, 3)
        U, _, Vt = np.linalg.svd(M)  # the nearest rotation (rounding in the recorded elements)
        return U @ Vt, ok & (np.linalg.det(M) > 0)
    if m.euler is not None:
        R = euler_to_matrix_ordered(np.where(ok[:, None], att * m.angle_scale, 0.0), m.euler)
        return R, ok
    q = att if m.quaternion == "wxyz" else att[:, [3, 0, 1, 2]]
    return tracked_matrices(q, ok), ok


def read_mapped(path: str, m: RecordingMap, *, frame: str | None = None,
                strict_frame: bool = False, max_dropout: float = MAX_DROPOUT,
                lines: list[str] | None = None) -> RawTake:
    """Read a lab's CSV take through the recording map `m` into a `RawTake` in
    north-east-down (module docstring).

    **Arguments:**
    - `path`: the take (a CSV file with one header row, or `.csv.gz`, or an array file);
      its pose is in the map's `[tracking] file` beside it where the map names one;
    - `m`: the recording map ([`fwid.reconstruction.read_map`][]);
    - `frame`: overrides the map's `[tracking] frame`;
    - `strict_frame`: refuse, instead of correcting, a pose convention the onboard sensors
      contradict;
    - `max_dropout`: the longest gap (s) bridged.
    """
    take = path
    path = str(m.tracking_path(take))
    if path != str(take):
        if not Path(path).is_file():
            raise FlightDataError(f"{take}: no pose file {Path(path).name} beside it (the map's "
                                  f"[tracking] file, {m.tracking_file!r}); put it there or fix "
                                  f"the map {m.path}")
        lines = None
    cols, notes = read_columns(path, m, True, lines)
    t = _time(cols, path, m, m.time_column, m.time_scale)
    _check_time_unit(t, path, m)
    cols, t, more = _merge_repeated_times(cols, t, path)
    notes += more
    grid, how, more = uniform_time(t, path, 2, m.time_column or m.frame_column)
    notes += more
    pos = _pick(cols, m.position, path, m) * m.position_scale
    att = _pick(cols, m.attitude, path, m)
    if m.quaternion is not None:
        ok = np.all(np.isfinite(att), 1)
        q = att if m.quaternion == "wxyz" else att[:, [3, 0, 1, 2]]
        check_quaternions(q, ok, t, path, 2)
    if m.euler is not None and m.angle_scale == 1.0:
        _check_radians(att, path, m)
    R, ok_att = _attitude_matrices(att, m, path)
    seen = ok_att & np.all(np.isfinite(pos), 1)
    quat, at = (np.where(seen[:, None], matrix_to_quat(R), np.nan),
                np.where(seen[:, None], pos, np.nan))
    held, tracking_rate, said = _slow_tracking(t, quat, at, seen, path,
                                               1.0 / float(np.median(np.diff(t))))
    notes += said
    # glitches (held poses, flips, jumps) are the same in any frame: dropped before the check
    if held is None:
        tracked, said = drop_glitches(t, quat, seen, at, path)
    else:  # a slower tracking's fresh poses alone: its repeats are no glitches
        fresh = np.flatnonzero(seen & ~held)
        tracked = np.zeros(len(t), bool)
        tracked[fresh], said = drop_glitches(t[fresh], quat[fresh], np.ones(len(fresh), bool),
                                             at[fresh], path, held=False)
        pos, att, tracked = _fill_held(t, pos, att, tracked, held, m)
        R, _ = _attitude_matrices(att, m, path)
    notes += said
    sensors = mapped_controls(cols, path, m) if m.log_is_take else {}
    convention = Convention(frame or m.frame, (1.0, 1.0, 1.0), m.axes)
    checked = "acc_x" in sensors or "p_gyro" in sensors
    if checked:
        f_flap = float(np.nanmedian(sensors["f"])) if "f" in sensors else None
        check_scales(t, pos, R, tracked, sensors, m, path, f_flap=f_flap)
        attitude = None
        if m.euler is not None:
            attitude = lambda signs: _attitude_matrices(att * np.array(signs), m, path)[0]  # noqa: E731
        convention, note = choose_convention(t, pos, R, tracked, sensors, convention,
                                             attitude=attitude, path=path, strict=strict_frame,
                                             f_flap=f_flap)
        if note:
            notes.append(note)
        if convention.sensor_axes != m.axes:
            sensors = mapped_controls(cols, path, m._replace(axes=convention.sensor_axes))
        if convention.angle_signs != (1.0, 1.0, 1.0):
            R, _ = _attitude_matrices(att * np.array(convention.angle_signs), m, path)
    pos, R = to_ned(pos, R, convention.frame)
    q = np.where(tracked[:, None], matrix_to_quat(R), np.nan)
    # onto the uniform grid: positions and sign-continuous quaternions, linear (renormalised)
    q = continuous_sign(q, tracked)
    seen = np.all(np.isfinite(onto_grid(np.where(seen[:, None], pos, np.nan), how)), 1)
    pos, q = onto_grid(np.where(tracked[:, None], pos, np.nan), how), onto_grid(q, how)
    sensors = {k: onto_grid(v, how) for k, v in sensors.items()}
    tracked = np.all(np.isfinite(pos), 1) & np.all(np.isfinite(q), 1)
    q = np.where(tracked[:, None], q / np.linalg.norm(np.where(tracked[:, None], q, 1.0), axis=1,
                                                      keepdims=True), np.nan)
    t = grid
    # the controls' own gaps (a log's empty cells) end the take where they start or stop it
    if sensors:
        tracked = tracked & np.all(np.isfinite(np.stack(list(sensors.values()), 1)), 1)
    cut = trim_untracked(t, pos, q, tracked, sensors, {"dropped": seen & ~tracked})
    if cut is None:
        raise FlightDataError(f"{path}: the pose is complete on fewer than 3 rows")
    t, pos, q, tracked, sensors, extra = cut
    if sensors:
        for k, v in sensors.items():
            good = np.isfinite(v)
            if not good.all():
                sensors[k] = np.interp(t, t[good], v[good])
    gaps = dropouts(t, tracked, path, max_dropout, extra["dropped"])
    log = None
    if not m.log_is_take:
        log = read_mapped_log(m.log_path(take), m, take)
    source = (f"recording map {m.path} ({convention.frame}"
              + (f", Euler {m.euler}" if m.euler else "")
              + (f", the pose from {Path(path).name}" if path != str(take) else "") + ")")
    return RawTake(take_name(take), str(take), source, convention.frame, t, pos, q, tracked,
                   sensors if m.log_is_take else None, log, gaps, notes,
                   convention if checked else None, tracking_rate)


def read_mapped_log(path, m: RecordingMap, take) -> OnboardLog | None:
    """The autopilot's log of its own (on its own clock) through the map: its time column
    and the mapped controls and sensors; None (no controls) when there is no such file."""
    if not Path(path).is_file():
        return None
    cols, _ = read_columns(path, m, take=False)
    t = _pick(cols, [m.log_time], path, m)[:, 0] * m.log_time_scale
    grid, how, _ = uniform_time(t, str(path), 2, m.log_time)
    out = {k: onto_grid(v, how) for k, v in mapped_controls(cols, path, m).items()}
    if "p_gyro" in out:
        out.update({k: out.pop(f"{k}_gyro") for k in "pqr"})
    return OnboardLog(str(path), grid, out)
