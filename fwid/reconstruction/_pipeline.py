"""From raw takes to section-1 flights: read, align the clocks, smooth, rebuild the loads.

Takes of one sample step are smoothed together (vmapped), padded to one length (a multiple
of `BUCKET` samples, unmeasured after each take's end); a take that fails is reported and
left out while the others go on. Reading the takes and aligning their clocks run one take
per task on worker processes where there are several cores and takes (`_workers.py`).
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._errors import FlightDataError, FwidError, InputError
from .._words import count
from ..data._checks import check_flight
from ..data._sidefiles import VEHICLE_FILE, read_vehicle
from ._airborne import cut_take
from ._attitude import smooth_attitude
from ._body_frame import compose, split
from ._checks import check_frame, residuals
from ._clock import MIN_OVERLAP, ClockOffset, find_offset, resample
from ._imu import agreement, frame_from_gyro
from ._loads import body_states, rigid_body_loads
from ._model import HARMONICS, phase_of
from ._raw import MAX_DROPOUT, RawTake
from ._map import RecordingMap, read_map
from ._read import raw_files, read_raw
from ._ripple import flapping_frequency
from ._shrink import coefficient_variance, shrink_harmonics
from ._smoother import _fns, smooth_batch
from ._workers import Failed, run_all, start

#: The section-1 columns written, in order (extras follow).
COLUMNS = ("t", "u", "v", "w", "p", "q", "r", "phi", "theta", "psi", "de", "dr", "f",
           "X", "Y", "Z", "L", "M", "N")


class ReconstructedFlight(NamedTuple):
    """One reconstructed take: `columns` (section 1 plus extras: `x y z` the smoothed
    position, `tracked`, the gyro `p_gyro q_gyro r_gyro` when there is one), its
    `reconstruction.json` entry, the `vehicle` used and what the figure shows (`raw`: the
    take as recorded, cut to the flight's time base)."""

    name: str
    columns: dict[str, np.ndarray]
    entry: dict
    vehicle: dict
    vehicle_path: str
    raw: dict[str, np.ndarray]


class Reconstruction(NamedTuple):
    """What [`fwid.reconstruct`][] made: the flights (in input order) and the takes that
    failed, as `(path, one-line message)`."""

    flights: list[ReconstructedFlight]
    failures: list[tuple[str, str]]


def _groups(items, key):
    out = defaultdict(list)
    for i, it in enumerate(items):
        out[key(it)].append(i)
    return out.values()


#: Takes are padded to a multiple of this many samples (unmeasured samples after the end),
#: so that takes of nearly one length run in one vmapped call of one compiled program.
BUCKET = 256


def _stack(xs, n=None, fill=0.0):
    """`xs` (time first) stacked, each padded to `n` samples (`fill`, or `"edge"`)."""
    if n is None:
        return np.stack(xs)
    out = []
    for x in xs:
        x = np.asarray(x)
        pad = [(0, n - len(x))] + [(0, 0)] * (x.ndim - 1)
        out.append(np.pad(x, pad, mode="edge") if fill == "edge"
                   else np.pad(x, pad, constant_values=fill))
    return np.stack(out)


def _bucket(lengths) -> int:
    return int(-(-max(lengths) // BUCKET) * BUCKET)


def _attitude(takes, quats, tracked, fs, gyros=None, gmasks=None, starts=None, params=None,
              passes=None, ends=None):
    """Smooth the attitude of several takes, vmapped by sample step and padded to one length
    (`passes`, `ends`: per take; `ends` as `smooth_attitude`'s, default True)."""
    out = [None] * len(takes)
    ends = [True] * len(takes) if ends is None else ends
    key = (lambda i: (round(takes[i].dt, 12), None if passes is None else passes[i], ends[i]))
    for idx in _groups(range(len(takes)), key):
        dt = takes[idx[0]].dt
        lens = np.array([len(tracked[i]) for i in idx])
        n = _bucket(lens)
        ph, om = zip(*(phase_of(fs[i], dt) for i in idx))
        kw = {}
        if gyros is not None:
            kw = {"gyro": _stack([gyros[i] for i in idx], n),
                  "gyro_mask": _stack([gmasks[i] for i in idx], n, False)}
        if starts is not None:
            kw["start"] = _stack([starts[i] for i in idx], n, "edge")
        if params is not None:
            kw["params"] = [p for i in idx for p in params[i]]
        if passes is not None:
            kw["passes"] = passes[idx[0]]
        kw["ends"] = ends[idx[0]]
        att = smooth_attitude(_stack([quats[i] for i in idx], n, np.nan),
                              _stack([tracked[i] for i in idx], n, False),
                              _stack(ph, n, "edge"), _stack(om, n, np.nan), dt, lengths=lens, **kw)
        for j, i in enumerate(idx):
            out[i] = type(att)(*(None if v is None else (v[3 * j:3 * j + 3] if k == "params" else
                                                         v[j, :lens[j]] if k in ("R", "w", "a") else v[j])
                                 for k, v in att._asdict().items()))
    return out


def _smooth_positions(takes, pos, tracked, fs, ends=True):
    """Smooth positions `(N, 3)` per axis (three problems a take), vmapped by sample step
    (`ends`: as `smooth_batch`)."""
    out = [None] * len(takes)
    for idx in _groups(range(len(takes)), lambda i: round(takes[i].dt, 12)):
        dt = takes[idx[0]].dt
        lens = np.array([len(tracked[i]) for i in idx])
        n = _bucket(lens)
        ph, om = zip(*(phase_of(fs[i], dt) for i in idx))
        sm = smooth_batch(_stack([pos[i] for i in idx], n, np.nan),
                          _stack([tracked[i] for i in idx], n, False),
                          _stack(ph, n, "edge"), _stack(om, n, np.nan), dt, scale=1e-6,
                          lengths=lens, ends=ends)
        for j, i in enumerate(idx):
            out[i] = type(sm)(*(v[j, :lens[j]] if k in ("pos", "vel", "acc", "slow") else
                                v[j] if isinstance(v, np.ndarray) else v
                                for k, v in sm._asdict().items()))
    return out


def _translation(takes, pos, tracked, fs, atts):
    """Position, velocity and acceleration with the flapping harmonics in body axes
    (`_body_frame`): a world-axis pass for the slow reference, then the remainder in the body
    axes of the smoothed attitudes `atts`. Noise levels and bandwidths: the second pass's."""
    refs = [tuple(f.slow[:, d, :] for d in range(3))
            for f in _smooth_positions(takes, pos, tracked, fs)]
    body = [split(p, r[0], a.R) for p, r, a in zip(pos, refs, atts)]  # NaN where untracked
    second = _smooth_positions(takes, body, tracked, fs, ends=False)  # its slow part is small
    return [s._replace(**dict(zip(("pos", "vel", "acc"),
                                  compose(r, (s.pos, s.vel, s.acc), a.R, a.w, a.a))))
            for s, r, a in zip(second, refs, atts)]


def _shrunk(att, f, dt, tracked):
    """`att` with the flapping harmonics of its rates that the take cannot resolve shrunk
    (`_shrink`): the variance of a rate coefficient of harmonic `k` from the attitude's
    noise, `(k W)^2` times the angle's, combined with the gyro's where there is one."""
    ph, om = phase_of(f, dt)
    n = int(np.sum(tracked))
    kw = np.arange(1, HARMONICS + 1)[:, None] * np.nanmedian(om)
    var = kw**2 * coefficient_variance(att.sigma, n)[None]
    if att.sigma_gyro is not None:
        var = 1.0 / (1.0 / var + 1.0 / coefficient_variance(att.sigma_gyro, len(f))[None])
    (w, a), _ = shrink_harmonics([att.w, att.a], ph, om, var, dt)
    return att._replace(w=w, a=a)


def _vehicle(path: Path, vehicle):
    if vehicle is not None:
        return (dict(vehicle), "") if isinstance(vehicle, dict) else (read_vehicle(vehicle), str(vehicle))
    v = path.parent / VEHICLE_FILE
    if not v.is_file():
        raise FlightDataError(f"{path}: no {VEHICLE_FILE} beside the take; the loads need the "
                              "vehicle's mass and inertia (see the guide's page on flight files)")
    return read_vehicle(v), str(v)


def _cut(take: RawTake, clock, min_overlap):
    """The take's samples covered by its log at the clock offset, and the log there."""
    log = take.onboard
    lo, hi = log.t[0] + clock.offset, log.t[-1] + clock.offset
    keep = (take.t >= lo - 1e-9) & (take.t <= hi + 1e-9) & np.isfinite(take.t)
    idx = np.flatnonzero(keep)
    if idx.size == 0 or (take.t[idx[-1]] - take.t[idx[0]]) < min_overlap:
        n = 0.0 if idx.size == 0 else take.t[idx[-1]] - take.t[idx[0]]
        raise FlightDataError(
            f"{take.path}: take and autopilot log {log.path} overlap for {n:.3g} s only at "
            f"the clock offset {clock.offset:.6g} s (at least {min_overlap:g} s needed); give "
            "the log of this take, or the right --clock-offset")
    s = slice(int(idx[0]), int(idx[-1]) + 1)
    cols = {k: resample(log.t, v, take.t[s] - clock.offset) for k, v in log.columns.items()}
    # the spline may leave the first/last sample NaN by round-off: hold the nearest value
    for k, v in cols.items():
        good = np.flatnonzero(np.isfinite(v))
        cols[k] = np.interp(np.arange(len(v)), good, v[good])
    return s, cols


def reconstruct(paths, *, body: str | None = None, frame: str | None = None, onboard=None,
                clock_offset: float | None = None, max_dropout: float = MAX_DROPOUT,
                min_overlap: float = MIN_OVERLAP, vehicle=None, progress=None,
                processes: int | None = None, pool=None, recording_map=None,
                strict_frame: bool = False, keep_ground: bool = False) -> Reconstruction:
    """Raw takes to flights (the flight files of 'Formats and interfaces'), smoothed, with loads.

    The states come from the smoother, the loads from the full nonlinear rigid-body
    equations; a take that fails is reported and the others go on.

    **Arguments:**
    - `paths`: raw takes (files, or folders of them): fwid raw CSVs or Motive CSV exports;
    - `body`, `frame`, `onboard`, `recording_map`, `strict_frame`: as
      [`fwid.read_raw`][] (a take with neither an autopilot log nor mapped controls is
      reconstructed from the pose alone, its flapping frequency from the pose's ripple);
    - `max_dropout`: the longest tracking loss (s) bridged; the take is split at longer
      ones and its longest airborne stretch kept (`_airborne.py`);
    - `keep_ground`: keep the whole record; by default each take is cut to where the
      vehicle is airborne (the cut named in its `warnings`);
    - `clock_offset`: `t_tracking = t_onboard + clock_offset` (s) for Motive takes, instead
      of finding it from the gyro;
    - `min_overlap`: the shortest overlap (s) of take and log accepted;
    - `vehicle`: a `vehicle.json` path or its dict (default: the one beside each take);
    - `progress`: called with a one-line message per take;
    - `processes`: worker processes for the per-take work (reading, clock alignment; default
      one per core from 4 takes on, 0: none); `pool`: a pool of them to use instead
      (`fwid.reconstruction._workers.start`), left running.

    **Returns:** a `fwid.reconstruction.Reconstruction`: `flights` (each a
    `ReconstructedFlight`: `columns`, `entry` of `reconstruction.json`, ...) and `failures`
    (`(path, one-line message)`).
    """
    if not max_dropout > 0:
        raise InputError(f"max_dropout must be positive seconds, got {max_dropout!r}")
    if recording_map is not None and not isinstance(recording_map, RecordingMap):
        recording_map = read_map(recording_map)
    files = raw_files(paths, recording_map)
    if onboard is not None and len(files) > 1:
        raise InputError(f"--onboard names the log of one take, but {len(files)} takes were given")
    own = pool is None
    pool = start(len(files), processes) if own else pool
    try:
        return _reconstruct(files, pool, body=body, frame=frame, onboard=onboard,
                            clock_offset=clock_offset, max_dropout=max_dropout,
                            min_overlap=min_overlap, vehicle=vehicle, progress=progress,
                            recording_map=recording_map, strict_frame=strict_frame,
                            keep_ground=keep_ground)
    finally:
        if own and pool is not None:
            pool.shutdown()


def _align(take: RawTake, w, sigma, clock_offset, min_overlap, f):
    """The clock offset of a take with an autopilot log (from the body rates `w` smoothed
    without the gyro, from attitudes of noise `sigma`; `f` the flapping frequency), the
    take's samples the log covers and the log's signals there. A log without a gyro is
    taken on the given offset, or as on the tracking's clock."""
    log = take.onboard
    if not all(c in log.columns for c in "pqr"):
        given = clock_offset is not None
        clock = ClockOffset(clock_offset if given else 0.0, 0.0, float("nan"), float("nan"), True)
        s, cols = _cut(take, clock, min_overlap)
        return s, cols, clock._replace(given=given)
    gyro = np.stack([log.columns[c] for c in "pqr"], 1)
    f0 = float(np.nanmedian(f))  # the log's median f where it has one (`_flapping`)
    clock = find_offset(take.t, w, log.t, gyro, f0,
                        given=clock_offset, min_overlap=min_overlap, sigma=sigma)
    if clock is None:
        at = ("any clock offset" if clock_offset is None
              else f"the clock offset {clock_offset:g} s given")
        raise FlightDataError(
            f"{take.path}: take and autopilot log {log.path} overlap by less than "
            f"{min_overlap:g} s at {at}; give the log of this take"
            + ("" if clock_offset is None else " or the right --clock-offset"))
    s, cols = _cut(take, clock, min_overlap)
    other = frame_from_gyro(take.t[s], w[s], np.stack([cols[k] for k in "pqr"], 1), take.frame,
                            f0)
    if other is not None:
        raise FlightDataError(
            f"{take.path}: the autopilot's gyro disagrees with the body rates of the take read "
            f"in the {take.frame} frame and agrees with them read in the {other[0]} frame "
            f"(cycle-averaged correlation p, q, r {', '.join(f'{c:.2f}' for c in other[1])}); "
            f"give --frame {other[0]}")
    return s, cols, clock


def _flapping(take: RawTake):
    """The flapping frequency (Hz) on the take's samples: logged (the autopilot log's
    median, the take's own `f` column), else from its tracked wings, else from the pose's
    ripple (NaN where there is none), and a note when it was not logged."""
    if take.onboard is not None and "f" in take.onboard.columns:
        return np.full(len(take.t), np.median(take.onboard.columns["f"])), None
    if take.controls is not None and "f" in take.controls:  # the take's own, or its wings'
        return take.controls["f"], None
    f, note = flapping_frequency(take.t, take.quat, take.tracked)
    return (np.full(len(take.t), np.nan) if f is None else f), note


def _reconstruct(files, pool, *, body, frame, onboard, clock_offset, max_dropout, min_overlap,
                 vehicle, progress, recording_map=None, strict_frame=False,
                 keep_ground=False) -> Reconstruction:
    say = progress or (lambda msg: None)
    failures, ok = {}, []
    # every gap read, however long: the take is split at those over max_dropout (_airborne)
    read = run_all(read_raw, [((f,), {"body": body, "frame": frame, "onboard": onboard,
                                      "max_dropout": np.inf, "recording_map": recording_map,
                                      "strict_frame": strict_frame}) for f in files], pool,
                   meanwhile=_fns)  # on workers: JAX imported and the programs made meanwhile
    for f, take in zip(files, read):
        try:
            if isinstance(take, Failed):
                raise FlightDataError(take.message)
            ok.append((f, take, *_vehicle(f, vehicle)))
        except FwidError as e:
            failures[str(f)] = str(e)
            say(f"{f.name}: failed (below)")
    # the airborne stretch of each take (the flapping frequency from the whole take)
    cut, names = [], {take.name for _, take, _, _ in ok}
    for f, take, veh, vpath in ok:
        try:
            fl, note = _flapping(take)
            take = take if note is None else take._replace(warnings=take.warnings + [note])
            pieces, _ = cut_take(take, fl, max_dropout=max_dropout, keep_ground=keep_ground,
                                 taken=names - {take.name})
            cut += [((f, piece, veh, vpath), fp) for piece, fp in pieces]
        except FwidError as e:
            failures[str(f)] = str(e)
            say(f"{f.name}: failed (below)")
    ok, fs = [c[0] for c in cut], [c[1] for c in cut]
    takes = [t for _, t, _, _ in ok]
    # 1. attitude without the gyro (the final one for a fwid raw CSV); the clock from it
    # one pass where the gyro's pass follows (it starts from this one's attitude), else two
    att0 = _attitude(takes, [t.quat for t in takes], [t.tracked for t in takes], fs,
                     passes=[1 if t.onboard is not None else 2 for t in takes],
                     ends=[not _gyro_follows(t) for t in takes])
    logged = [i for i, t in enumerate(takes) if t.onboard is not None]
    tasks = [((takes[i], att0[i].w, att0[i].sigma, clock_offset, min_overlap, fs[i]), {})
             for i in logged]
    aligned = dict(zip(logged, run_all(_align, tasks, pool)))
    flights, stage = [None] * len(ok), []
    for i, (f, take, veh, vpath) in enumerate(ok):
        if take.onboard is None:
            cols = dict(take.controls or {})
            cols.setdefault("f", fs[i])
            for k in "pqr":  # columns p q r of a fwid raw CSV are not a gyro; a map's are
                cols.pop(k, None)
                if f"{k}_gyro" in cols:
                    cols[k] = cols.pop(f"{k}_gyro")
            stage.append((i, slice(None), cols, None, att0[i]))
        elif isinstance(aligned[i], Failed):
            failures[_key(f, take)] = aligned[i].message
            say(f"{f.name}: failed (below)")
        else:
            s, cols, clock = aligned[i]
            cols.setdefault("f", fs[i][s])  # a log without f: the take's
            stage.append((i, s, cols, clock, att0[i]))
    # 2. attitude with the gyro, about the first pass's attitude; translation
    with_gyro = [st for st in stage if _gyro(st)]
    att1 = _attitude([ok[i][1] for i, *_ in with_gyro],
                     [ok[i][1].quat[s] for i, s, *_ in with_gyro],
                     [ok[i][1].tracked[s] for i, s, *_ in with_gyro],
                     [c["f"] for _, _, c, _, _ in with_gyro],
                     gyros=[np.stack([c[k] for k in "pqr"], 1) for _, _, c, _, _ in with_gyro],
                     gmasks=[np.ones(len(c["f"]), bool) for _, _, c, _, _ in with_gyro],
                     starts=[a.R[s] for _, s, _, _, a in with_gyro],
                     params=[a.params for *_, a in with_gyro], passes=[1] * len(with_gyro))
    gyro_att = {st[0]: a for st, a in zip(with_gyro, att1)}
    final_att = {i: _shrunk(gyro_att.get(i, a0), c["f"], ok[i][1].dt, ok[i][1].tracked[s])
                 for i, s, c, _, a0 in stage}
    trans = _translation([ok[i][1] for i, *_ in stage], [ok[i][1].pos[s] for i, s, *_ in stage],
                         [ok[i][1].tracked[s] for i, s, *_ in stage],
                         [c["f"] for _, _, c, _, _ in stage],
                         [final_att[i] for i, *_ in stage])
    for (i, s, cols, clock, _), tr in zip(stage, trans):
        f, take, veh, vpath = ok[i]
        try:
            att = final_att[i]
            flights[i] = _assemble(take, s, cols, clock, att, tr, veh, vpath)
            e = flights[i].entry
            off = f", clock offset {e['clock_offset_s']:.4f} s" if clock is not None else ""
            say(f"{take.name}: {len(flights[i].columns['t'])} samples at {e['rate_hz']:.4g} Hz"
                f"{off}, {count(len(e['dropouts']), 'dropout')}")
        except FwidError as e:
            failures[_key(f, take)] = str(e)
            say(f"{f.name}: failed (below)")
    order = {str(f): k for k, f in enumerate(files)}
    fails = sorted(failures.items(),
                   key=lambda kv: order.get(kv[0], order.get(kv[0].rsplit(" (", 1)[0], 0)))
    return Reconstruction([fl for fl in flights if fl is not None], fails)


def _key(f, take: RawTake) -> str:
    """What a failure is filed under: the file, and which of its flights when it gives
    several (a flight of a take split into stretches may fail while the others go on)."""
    several = take.stretch is not None and take.stretch["of"] > 1
    return f"{f} ({take.name})" if several else str(f)


def _gyro_follows(take: RawTake) -> bool:
    """Whether the take will have a gyro when staged (`_gyro`: its log's `p q r`, or the
    `p_gyro ..` its map names in the take): its attitude is then smoothed again with it."""
    names = (take.onboard.columns if take.onboard is not None else
             {k.removesuffix("_gyro") for k in take.controls or {} if k.endswith("_gyro")})
    return all(k in names for k in "pqr")


def _gyro(stage) -> bool:
    """Whether a staged take has a gyro (its log's, or one its map names)."""
    return all(k in stage[2] for k in "pqr")


def _assemble(take: RawTake, s, cols, clock, att, tr, veh, vpath) -> ReconstructedFlight:
    """A staged take's flight: `cols` holds the controls, `f` (NaN where the take shows no
    flapping: then no `f` column) and the gyro `p q r` when it has one."""
    t = take.t[s]
    if not np.isfinite(cols["f"]).any():
        cols = {k: v for k, v in cols.items() if k != "f"}
    has_gyro = all(k in cols for k in "pqr")
    V, dV, eul = body_states(att.R, tr.vel, tr.acc, att.w)
    XYZ, LMN = rigid_body_loads(V, dV, att.w, att.a, att.R, veh)
    check_frame(XYZ / veh["mass"], veh["g"], take)
    out = {"t": t}
    for k, v in zip(("u", "v", "w"), V.T):
        out[k] = v
    for k, v in zip(("p", "q", "r"), att.w.T):
        out[k] = v
    for k, v in zip(("phi", "theta", "psi"), eul.T):
        out[k] = v
    for k in ("de", "dr", "f"):
        if k in cols:
            out[k] = cols[k]
    for k, v in zip(("X", "Y", "Z", "L", "M", "N"), np.concatenate([XYZ, LMN], 1).T):
        out[k] = v
    for k, v in zip(("x", "y", "z"), tr.pos.T):
        out[k] = v
    tracked = take.tracked[s]
    out["tracked"] = tracked.astype(float)
    gyro = None
    if has_gyro:
        gyro = np.stack([cols[k] for k in "pqr"], 1)
        for k in "pqr":
            out[f"{k}_gyro"] = cols[k]
    for k, v in cols.items():
        if k not in out and k not in ("p", "q", "r"):
            out[k] = v
    lo, hi = t[0], t[-1]
    gaps = [g for g in take.dropouts if g[1] >= lo and g[0] <= hi]
    res = residuals(take.pos[s], take.quat[s], tracked, tr.pos, att.R, att.w, gyro, att.bias)
    warnings = list(take.warnings)
    entry = {
        "flight": f"{take.name}.csv", "source": f"{take.source}: {Path(take.path).name}",
        "clock_offset_s": 0.0 if clock is None else clock.offset,
        "dropouts": gaps, "warnings": warnings,
        **({} if take.stretch is None else {"stretch": take.stretch}),
        "rate_hz": 1.0 / take.dt, "duration_s": float(t[-1] - t[0]),
        **({} if take.tracking_rate is None else {"tracking_rate_hz": take.tracking_rate}),
        "clock": None if clock is None else {
            "offset_s": clock.offset, "std_s": clock.std, "corr": clock.corr,
            "rms_rad_s": clock.rms, "given": clock.given},
        "noise": {"position_m": float(tr.sigma), "attitude_rad": list(att.sigma),
                  "gyro_rad_s": None if att.sigma_gyro is None else list(att.sigma_gyro)},
        "smoother": {"position_cutoff_hz": float(tr.cutoff),
                     "position_harmonic_bandwidth_hz": float(tr.coeff_bandwidth),
                     "attitude_cutoff_hz": list(att.cutoff),
                     "attitude_harmonic_bandwidth_hz": list(att.coeff_bandwidth)},
        "gyro_bias_rad_s": None if att.bias is None else list(att.bias),
        "residuals": res,
        "specific_force_body_mean": list(np.mean(XYZ, 0) / veh["mass"]),
    }
    imu = agreement(t, XYZ / veh["mass"], att.w,
                    {**{k: v for k, v in cols.items() if k.startswith("acc_")},
                     **({f"{k}_gyro": cols[k] for k in "pqr"} if has_gyro else {})},
                    float(np.nanmedian(cols["f"])) if "f" in cols else None, att.bias)
    if imu:
        conv = take.convention
        imu["frame"] = (conv.describe() if conv is not None
                        else f"{take.frame} frame, as read (not checked)")
        entry["imu"] = imu
    if clock is not None and not clock.given and not np.isfinite(clock.corr):
        warnings.append("the autopilot log has no gyro to align its clock by: the two clocks "
                        "are taken as one; give --clock-offset if they are not")
    if clock is not None and not clock.given and clock.corr < 0.5:
        warnings.append(f"the clock offset is poorly determined (gyro and smoothed rates "
                        f"correlate at {clock.corr:.2f}); check the log, or give --clock-offset")
    if res["position_rms_m"] > 3 * tr.sigma or max(res["attitude_rms_rad"]) > 3 * max(att.sigma):
        warnings.append("the smoothed motion departs from the recorded by more than 3 noise "
                        "levels; check the take for glitches")
    try:  # never an output that fwid itself refuses
        check_flight(f"{take.name}.csv", t, {k: v for k, v in out.items() if k != "t"})
    except FlightDataError as e:
        raise FlightDataError(f"{take.path}: the reconstructed flight fails the flight checks "
                              f"({e}); check the take for glitches and its frame") from None
    raw = {"t": t, "pos": take.pos[s], "quat": take.quat[s], "tracked": tracked}
    if gyro is not None:
        raw["gyro"] = gyro
    return ReconstructedFlight(take.name, out, entry, veh, vpath, raw)
