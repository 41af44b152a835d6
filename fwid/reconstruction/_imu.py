"""The onboard sensors against the pose: which convention the pose was recorded in, and how
well the reconstruction agrees with the accelerometer and the gyro.

An accelerometer measures the specific force `R^T (a - g)` in body axes, a gyro the body
rates; both follow from the tracked pose alone. Under a wrong frame (gravity along the wrong
world axis), a wrong sign of an Euler angle (a logger's pitch positive nose down) or wrong
sensor axes (forward-left-up read as forward-right-down) the two disagree by about `g`, far
beyond what noise and flapping leave once both are averaged over the flapping cycle.

**Choosing the convention.** Every candidate (the three frames; the eight sign patterns of
the Euler angles when the attitude is Euler angles; both sensor axes) is scored by the
error energy of the cycle-averaged sensor signals against the same signals computed naively
from the pose under that candidate (a Savitzky-Golay second derivative of the position),
relative to the sensor signal's own energy, summed over the sensors mapped. The candidates
within `TIE` of the best score are the ones the data support; of those, the one with the
fewest changes from the map's is used. So the map's own convention is kept whenever the
data support it, and replaced only when another fits clearly better; when no candidate
agrees (correlation of the best below `AGREE` on every axis), the map's is kept and the
warning says so.

**Agreement.** `reconstruction.json` reports, per flight, for each sensor and body axis the
correlation `corr` and rms difference `rms` of the cycle-averaged sensor signal and the one
reconstructed (the specific force `(X, Y, Z) / m`, the body rates less the gyro's bias).
"""

from __future__ import annotations

from itertools import product
from typing import NamedTuple

import numpy as np

from .._errors import FlightDataError
from ._clock import lowpass
from ._rotations import FRAMES, log_so3, to_ned

#: The cycle average of the comparisons: a low-pass at this cut-off (Hz), or at
#: `CUTOFF_FRACTION` of the flapping frequency where that is lower.
CUTOFF = 5.0
CUTOFF_FRACTION = 0.4
#: Candidates whose score is within this fraction of the best are supported by the data.
TIE = 0.25
#: The best candidate agrees when its correlation reaches this on some axis.
AGREE = 0.5
#: Standard gravity (m/s^2): an accelerometer's g.
G0 = 9.80665
#: The sensors' axes -> forward-right-down.
SENSOR_TO_FRD = {"frd": np.ones(3), "flu": np.array([1.0, -1.0, -1.0])}
ACC = ("acc_x", "acc_y", "acc_z")
GYRO = ("p_gyro", "q_gyro", "r_gyro")
#: Savitzky-Golay window of the naive derivatives (s) and polynomial order.
SG_WINDOW = 0.3
SG_ORDER = 3


class Convention(NamedTuple):
    """How a pose and its sensors were recorded: the tracking `frame` (`ned`, `y-up`,
    `z-up`), a sign per Euler angle (roll, pitch, yaw) and the sensors' body axes."""

    frame: str
    angle_signs: tuple[float, float, float]
    sensor_axes: str

    def describe(self) -> str:
        names = [n for n, s in zip(("roll", "pitch", "yaw"), self.angle_signs) if s < 0]
        signs = f", {' and '.join(names)} reversed" if names else ""
        return f"{self.frame} frame{signs}, sensors {self.sensor_axes.upper()}"


def cycle_average(t: np.ndarray, x: np.ndarray, f_flap: float | None = None) -> np.ndarray:
    """`x` low-passed below the flapping cycle (module constants)."""
    fc = CUTOFF if not f_flap or not np.isfinite(f_flap) else min(CUTOFF, CUTOFF_FRACTION * f_flap)
    return lowpass(t, x, fc)


def _filled(x, ok):
    idx = np.flatnonzero(ok)
    n = np.arange(len(x))
    return np.stack([np.interp(n, idx, c[idx]) for c in np.asarray(x, float).T], 1)


def naive_motion(t: np.ndarray, pos: np.ndarray, R: np.ndarray, tracked: np.ndarray, g: float):
    """The specific force `(n, 3)` (body axes, m/s^2) and body rates `(n, 3)` (rad/s) from a
    pose in north-east-down, naively: a Savitzky-Golay second derivative of the position
    (gaps interpolated) and finite differences of the attitude. The peer that any lab would
    write, and what the frame candidates are judged by."""
    from scipy.signal import savgol_filter

    dt = float(np.median(np.diff(t)))
    win = max(SG_ORDER + 2, int(round(SG_WINDOW / dt)) | 1)
    win = min(win, (len(t) - 1) | 1 if len(t) % 2 == 0 else len(t))  # a short take: all of it
    p = _filled(pos, tracked)
    a = savgol_filter(p, win, SG_ORDER, deriv=2, delta=dt, axis=0, mode="interp")
    Rf = np.where(tracked[:, None, None], R, np.eye(3))
    f = np.einsum("nji,nj->ni", Rf, a - np.array([0.0, 0.0, g]))
    rel = np.swapaxes(Rf[:-1], -1, -2) @ Rf[1:]
    w = log_so3(rel) / dt
    w = np.concatenate([w[:1], 0.5 * (w[1:] + w[:-1]), w[-1:]])
    both = tracked.copy()
    both[1:] &= tracked[:-1]
    return f, w, tracked & both


def sensor_arrays(sensors: dict) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The accelerometer `(n, 3)` and gyro `(n, 3)` of mapped sensor columns, or None."""
    acc = np.stack([sensors[k] for k in ACC], 1) if ACC[0] in sensors else None
    gyro = np.stack([sensors[k] for k in GYRO], 1) if GYRO[0] in sensors else None
    return acc, gyro


def _averaged(t, a, b, ok, f_flap, centre):
    """Cycle averages of sensor `a` and pose `b` `(n, 3)` on the rows where both are good
    (means removed when `centre`), or None with fewer than 20 such rows."""
    good = ok & np.all(np.isfinite(a), 1) & np.all(np.isfinite(b), 1)
    if good.sum() < 20:
        return None
    a = cycle_average(t, _filled(a, good), f_flap)[good]
    b = cycle_average(t, _filled(b, good), f_flap)[good]
    if centre:
        a, b = a - a.mean(0), b - b.mean(0)
    return a, b


def _stats(a, b):
    """Relative error energy of `b` against `a`, and per axis the correlations and rms."""
    energy = float(np.sum((a - b) ** 2) / max(np.sum(a**2), 1e-12))
    corr = [float(np.corrcoef(a[:, i], b[:, i])[0, 1]) if np.std(a[:, i]) * np.std(b[:, i]) > 0
            else 0.0 for i in range(3)]
    rms = [float(v) for v in np.sqrt(np.mean((a - b) ** 2, 0))]
    return energy, corr, rms


def _compare(t, a, b, ok, f_flap, centre):
    """`_stats` of the cycle averages of sensor `a` and pose `b` (`_averaged`), or None."""
    ab = _averaged(t, a, b, ok, f_flap, centre)
    return None if ab is None else _stats(*ab)


#: The sensors' scale against the pose's is judged within this factor either way.
SCALE_FACTOR = 3.0


def check_scales(t, pos, R, tracked, sensors, m, path: str, g: float = G0,
                 f_flap: float | None = None) -> None:
    """Refuse mapped sensors whose unit is off: averaged over the flapping cycle, an
    accelerometer on a vehicle in flight or at rest reads about `g`, and a gyro's rates are
    as large as the pose's (both sizes the same in any frame and axes). Outside
    `SCALE_FACTOR` either way, a `FlightDataError` names the map's key and the unit the
    numbers look like."""
    acc, gyro = sensor_arrays(sensors)
    if acc is not None:
        ok = np.all(np.isfinite(acc), 1)
        if ok.sum() >= 20:
            size = float(np.median(np.linalg.norm(cycle_average(t, _filled(acc, ok), f_flap)[ok],
                                                  axis=1)))
            ratio = size / g
            if not 1 / SCALE_FACTOR <= ratio <= SCALE_FACTOR:
                unit = ('acc_unit = "g"' if ratio < 1 else 'acc_unit = "m/s2"')
                raise FlightDataError(
                    f"{path}: the accelerometer reads {size:.3g} m/s^2 averaged over the flight "
                    f"with the map's acc_unit, where a vehicle in flight or at rest reads about "
                    f"g ({g:.3g}): its unit looks wrong; try {unit} in [onboard] of {m.path}")
    if gyro is not None:
        _, w, ok = naive_motion(t, pos, R, tracked, g)
        ok = ok & np.all(np.isfinite(gyro), 1)
        if ok.sum() >= 20:
            a = np.sqrt(np.mean(np.sum(gyro[ok] ** 2, 1)))
            b = np.sqrt(np.mean(np.sum(w[ok] ** 2, 1)))
            ratio = a / b if b > 0 else np.inf
            if not 1 / SCALE_FACTOR <= ratio <= SCALE_FACTOR:
                unit = 'gyro_unit = "deg/s"' if ratio > 1 else 'gyro_unit = "rad/s"'
                raise FlightDataError(
                    f"{path}: the gyro's rates are {ratio:.3g} times the pose's with the map's "
                    f"gyro_unit; try {unit} in [onboard] of {m.path}")


def choose_convention(t, pos, R, tracked, sensors, default: Convention, *, attitude=None,
                      path: str, strict: bool = False, g: float = G0,
                      f_flap: float | None = None):
    """The pose convention the onboard sensors support (module docstring).

    **Arguments:** `t`, `pos` `(n, 3)` and body -> world `R` `(n, 3, 3)` as recorded (the
    map's units applied, not yet turned into north-east-down), `tracked`; `sensors`: the
    mapped sensors under the map's axes (`acc_x ..`, `p_gyro ..`, forward-right-down);
    `default`: the map's convention; `attitude`: for Euler angles, the matrices with the
    angles' signs given (`attitude((1, -1, 1))`), whose sign patterns are then candidates;
    `strict`: refuse instead of correcting; `f_flap`: the flapping frequency (Hz).

    **Returns:** `(convention, warning or "")`.
    """
    acc, gyro = sensor_arrays(sensors)
    # the rows a sensor and the pose both hold do not depend on the candidate (the pose's
    # are the tracking's), nor do the sensors' cycle averages: each averaged once, its axes
    # relabelled per candidate
    ok = naive_motion(t, pos, R, tracked, g)[2]
    here = []  # (which pose signal, its rows, the sensor's cycle average, centred)
    for i, s_, centre in ((0, acc, False), (1, gyro, True)):  # a gyro's bias: not the pose's
        if s_ is None:
            continue
        good = ok & np.all(np.isfinite(s_), 1)
        if good.sum() >= 20:
            here.append((i, good, cycle_average(t, _filled(s_, good), f_flap)[good], centre))
    results = {}
    for signs in (list(product((1.0, -1.0), repeat=3)) if attitude is not None else [(1.0,) * 3]):
        Rs = R if signs == (1.0, 1.0, 1.0) else attitude(signs)
        for frame in FRAMES:
            p_ned, R_ned = to_ned(pos, Rs, frame)
            fw = naive_motion(t, p_ned, R_ned, tracked, g)[:2]
            mine = [cycle_average(t, _filled(fw[i], good), f_flap)[good]
                    for i, good, _, _ in here]
            for axes in SENSOR_TO_FRD:
                k = SENSOR_TO_FRD[axes] * SENSOR_TO_FRD[default.sensor_axes]
                score, corr = 0.0, []
                for b, (_, _, a, centre) in zip(mine, here):
                    a = a * k
                    if centre:
                        a, b = a - a.mean(0), b - b.mean(0)
                    energy, c, _ = _stats(a, b)
                    score, corr = score + energy, corr + c
                results[Convention(frame, signs, axes)] = (score, corr)
    best = min(results, key=lambda c: results[c][0])
    best_score, best_corr = results[best]
    if not best_corr or max(best_corr) < AGREE:
        return default, ("the onboard sensors agree with the pose under no convention tried "
                         f"(best correlation {max(best_corr, default=0):.2f}); the map's "
                         f"{default.describe()} is used unchecked")
    supported = [c for c in results if results[c][0] <= (1 + TIE) * best_score]

    def changes(c):
        return ((c.frame != default.frame) + (c.sensor_axes != default.sensor_axes)
                + sum(a != b for a, b in zip(c.angle_signs, default.angle_signs)))

    chosen = min(supported, key=lambda c: (changes(c), results[c][0]))
    if chosen == default:
        return default, ""
    which = " and ".join(n for n, s in (("accelerometer", acc), ("gyro", gyro)) if s is not None)
    fmt = lambda c: ", ".join(f"{v:.2f}" for v in results[c][1][:3])  # noqa: E731
    verb = "" if " and " in which else "s"
    msg = (f"the onboard {which} disagree{verb} with the pose as the map reads it "
           f"({default.describe()}: cycle-averaged correlation x, y, z {fmt(default)}) and "
           f"agree{verb} with it read as {chosen.describe()} ({fmt(chosen)})")
    if strict:
        raise FlightDataError(f"{path}: {msg}; fix the map, or drop --strict-frame to use "
                              "the convention that agrees")
    return chosen, msg + "; that reading is used (--strict-frame refuses instead)"


def frame_from_gyro(t, rates, gyro, frame: str, f_flap=None) -> tuple[str, list[float]] | None:
    """The tracking frame a gyro supports, when it is not `frame` (the one the take was read
    in), else None. A take read in frame `F` whose truth is `G` has body rates `D w` with
    `D = C_F C_G^T` (the frames' maps to north-east-down): each frame's rates `D^T w` are
    scored against the gyro (bias removed, cycle-averaged) as in `choose_convention`.

    **Returns:** `(frame, correlations per axis)` of the supported frame, or None."""
    ab = _averaged(t, gyro, rates, np.ones(len(t), bool), f_flap, centre=True)
    if ab is None:
        return None
    # the cycle average is linear: averaged once, relabelled per frame
    scores = {g: _stats(ab[0], ab[1] @ (FRAMES[frame] @ FRAMES[g].T)) for g in FRAMES}
    best = min(scores, key=lambda g: scores[g][0])
    if best == frame or scores[frame][0] <= (1 + TIE) * scores[best][0] \
            or max(scores[best][1]) < AGREE:
        return None
    return best, scores[best][1]


def agreement(t, specific_force, rates, sensors, f_flap=None, bias=None) -> dict:
    """The `imu` block of `reconstruction.json`: for the accelerometer (against the
    reconstructed specific force `(n, 3)`, m/s^2) and the gyro (less its `bias`, against the
    smoothed body rates, rad/s), per body axis `corr` and `rms` of the cycle averages."""
    acc, gyro = sensor_arrays(sensors)
    ok = np.ones(len(t), bool)
    out = {}
    for name, s, mine in (("acc", acc, specific_force), ("gyro", gyro, rates)):
        if s is None:
            continue
        if name == "gyro" and bias is not None:
            s = s - np.asarray(bias)
        r = _compare(t, s, mine, ok, f_flap, centre=False)
        if r is not None:
            out[name] = {ax: {"corr": c, "rms": e} for ax, c, e in zip("xyz", r[1], r[2])}
    return out
