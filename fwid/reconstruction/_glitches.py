"""Samples the tracking got wrong: held values, orientation flips and position jumps.

A tracking system that loses a rigid body may hold its last pose (the same numbers, to the
last digit, on the next frames): those frames are no measurements. A rigid body whose markers
are confused (swapped, or fitted the wrong way round) jumps to another orientation, often by
90-180 deg, for one frame or a few, and back: farther in one frame than any vehicle turns.
Both are dropped (`tracked` False) and bridged by the smoother like any dropout; what was
dropped is counted and named in the take's `warnings`.

How far is too far is judged from the take itself: the frame-to-frame rotation angle's median
plus `SPREAD` robust standard deviations (from the median absolute deviation), never less than
what a fast vehicle turns in a frame (`MAX_TURN_RATE`); the position alike (`MAX_SPEED`). From
the longest stretch without such a jump, the take is followed forward and backward: a sample is
kept when it lies within that bound of the last sample kept, the bound growing with the time
between them (so that the tracking locks on again after a glitch).
"""

from __future__ import annotations

import numpy as np

from .._errors import FlightDataError
from .._words import count

#: The physical floor of the bound (rad/s): no flying vehicle turns faster (1000 deg/s).
MAX_TURN_RATE = np.deg2rad(1000.0)
#: The physical floor of the bound on the position (m/s).
MAX_SPEED = 20.0
#: The bound above the median frame-to-frame step, in robust standard deviations.
SPREAD = 10.0
#: The largest share of a take's tracked frames that may be glitches; beyond, the take is
#: refused (its rigid body is not trustworthy).
MAX_GLITCH_FRACTION = 0.05
#: How many glitch times a warning names.
NAMED = 5


def _angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angles (rad) between unit quaternions `a` and `b` (either sign)."""
    dot = np.abs(np.einsum("ij,ij->i", a, b))
    return 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))


def _bound(steps: np.ndarray, floor: float) -> float:
    """The largest credible step per frame: `median + SPREAD` robust standard deviations of
    `steps`, at least `floor`."""
    if steps.size == 0:
        return floor
    med = float(np.median(steps))
    mad = float(np.median(np.abs(steps - med)))
    return max(floor, med + SPREAD * 1.4826 * mad)


def held_frames(quat: np.ndarray, pos: np.ndarray, tracked: np.ndarray) -> np.ndarray:
    """The tracked frames whose pose (all seven numbers) repeats the previous frame's exactly:
    a value held by the tracking software, not a measurement."""
    same = np.zeros(len(tracked), bool)
    same[1:] = (tracked[1:] & tracked[:-1] & np.all(quat[1:] == quat[:-1], axis=1)
                & np.all(pos[1:] == pos[:-1], axis=1))
    return same


def _follow(order, q, p, t, bound_q, bound_p, dt):
    """Keep, walking the samples `order`, those within the bounds (per frame, growing with the
    time since the last sample kept) of the last one kept; the first is kept. Returns the
    rejected samples and, for each, whether its orientation (else its position) failed."""
    rejected, by_angle = [], []
    j = order[0]
    qj, pj, tj = q[j], None if p is None else p[j], t[j]
    for i in order[1:]:
        frames = abs(t[i] - tj) / dt
        qi = q[i]
        dot = abs(qi[0] * qj[0] + qi[1] * qj[1] + qi[2] * qj[2] + qi[3] * qj[3])
        ang = 2.0 * np.arccos(min(dot, 1.0))
        bad_q = ang > bound_q * frames
        bad_p = False
        if p is not None:
            pi = p[i]
            dist = ((pi[0] - pj[0]) ** 2 + (pi[1] - pj[1]) ** 2 + (pi[2] - pj[2]) ** 2) ** 0.5
            bad_p = dist > bound_p * frames
        if bad_q or bad_p:
            rejected.append(i)
            by_angle.append(bad_q)
        else:
            qj, tj = qi, t[i]
            if p is not None:
                pj = p[i]
    return rejected, by_angle


def _times(t: np.ndarray, idx) -> str:
    """The times of samples `idx`, runs of neighbouring samples as `a-b`, the first `NAMED`
    runs named."""
    idx = np.unique(np.asarray(idx, int))
    cuts = np.flatnonzero(np.diff(idx) > 1) + 1
    runs = [(r[0], r[-1]) for r in np.split(idx, cuts)]
    shown = ", ".join(f"{t[a]:.4g}" if a == b else f"{t[a]:.4g}-{t[b]:.4g}"
                      for a, b in runs[:NAMED])
    return shown + (", ..." if len(runs) > NAMED else "") + " s"


def drop_glitches(t: np.ndarray, quat: np.ndarray, tracked: np.ndarray,
                  pos: np.ndarray | None = None, path: str = "", held: bool = True,
                  max_fraction: float = MAX_GLITCH_FRACTION) -> tuple[np.ndarray, list[str]]:
    """Drop the samples the tracking got wrong (module docstring).

    **Arguments:**
    - `t` `(n,)` (s): the time base (uniform, gaps allowed); `quat` `(n, 4)`: unit
      quaternions (either sign), NaN where `tracked` is False; `pos` `(n, 3)` (m), optional:
      its jumps count too;
    - `path`: the take (for messages); `held`: drop the frames that repeat the previous pose
      exactly (needs `pos`);
    - `max_fraction`: the largest share of the tracked frames that may be glitches.

    **Returns:** `(tracked, warnings)`: `tracked` with the dropped samples False, and one
    warning per kind of sample dropped (how many, and when). More glitches than `max_fraction`
    of the tracked frames is a `FlightDataError` naming them.
    """
    tracked = np.asarray(tracked, bool).copy()
    warnings = []
    same = np.zeros(len(tracked), bool)
    if held and pos is not None:
        same = held_frames(quat, pos, tracked)
        if same.any():
            tracked &= ~same
            verb = "repeats" if int(same.sum()) == 1 else "repeat"
            warnings.append(f"{count(int(same.sum()), 'frame')} {verb} the previous frame's pose exactly "
                            "(a value the tracking held, not a measurement): dropped as "
                            f"dropouts, at t = {_times(t, np.flatnonzero(same))}")
    idx = np.flatnonzero(tracked)
    if idx.size < 3:
        return tracked, warnings
    dt = float(np.median(np.diff(t)))
    nxt = np.diff(idx) == 1  # pairs of neighbouring frames: the take's own steps
    ang = _angles(quat[idx[1:]], quat[idx[:-1]])
    bound_q = _bound(ang[nxt], MAX_TURN_RATE * dt)
    jump = ang > bound_q * np.diff(t[idx]) / dt
    bound_p = None
    if pos is not None:
        dist = np.linalg.norm(pos[idx[1:]] - pos[idx[:-1]], axis=1)
        bound_p = _bound(dist[nxt], MAX_SPEED * dt)
        jump |= dist > bound_p * np.diff(t[idx]) / dt
    if not jump.any():
        return tracked, warnings
    # the longest stretch without a jump anchors the walk, forward and backward
    cuts = np.concatenate([[0], np.flatnonzero(jump) + 1, [idx.size]])
    k = int(np.argmax(np.diff(cuts)))
    start = int(cuts[k])
    q, p, tl = quat.tolist(), None if pos is None else pos.tolist(), t.tolist()
    fwd = _follow(idx[start:].tolist(), q, p, tl, bound_q, bound_p, dt)
    bwd = _follow(idx[start::-1].tolist(), q, p, tl, bound_q, bound_p, dt)
    rejected = fwd[0] + bwd[0]
    by_angle = np.array(fwd[1] + bwd[1], bool)
    if not rejected:
        return tracked, warnings
    rejected = np.array(rejected)
    flips, jumps = rejected[by_angle], rejected[~by_angle]
    if rejected.size > max_fraction * idx.size:
        held_too = (f"; {int(same.sum())} more frames only repeat the previous pose"
                    if same.any() else "")
        raise FlightDataError(
            f"{path}: {rejected.size} of {idx.size} tracked frames are glitches "
            f"({flips.size} orientation flips, {jumps.size} position jumps, at t = "
            f"{_times(t, rejected)}{held_too}), more than {max_fraction:.0%}: the rigid "
            "body's markers are confused; re-create the rigid body in the tracking software "
            "(markers placed asymmetrically), or cut the take to where it is tracked well")
    tracked[rejected] = False
    if flips.size:
        warnings.append(f"{count(flips.size, 'orientation glitch', 'orientation glitches')} "
                        "(flips) dropped, at t = "
                        f"{_times(t, flips)} (a turn faster than {np.rad2deg(bound_q / dt):.4g} "
                        "deg/s within one frame)")
    if jumps.size:
        warnings.append(f"{count(jumps.size, 'position jump')} (markers swapped) dropped, at t = "
                        f"{_times(t, jumps)} (faster than {bound_p / dt:.3g} m/s within one "
                        "frame)")
    return tracked, warnings
