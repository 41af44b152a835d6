"""Where a take is airborne: the rests on the ground found from the pose (and the wing beat
where the take logs it), and the take cut to its longest airborne stretch between them and
between tracking losses too long to bridge.

**The rule.** A sample is *on the ground* when the vehicle rests there, or when its wings are
known to stand still:

- *rests*: still (the position's spread over `WINDOW` seconds about the sample below `STILL`)
  and low (within `CLEARANCE` of the lowest height at which the vehicle is still anywhere in
  the take: the floor it rests on);
- *wings at rest*: the logged flapping frequency is not positive (no vehicle flies so, and
  a flight file's `f` must be positive).

An airborne stretch runs between two stretches on the ground, from where the height first
clears the rest's height before it by `CLEARANCE` to where it last clears the rest's height
after it by `CLEARANCE` (lift-off and touch-down, in ground effect and with the floor's
reaction in the loads, are left out whatever their duration); a stretch that never clears
it (a hop, the vehicle pushed over the floor) is not a flight. Stretches are split where the
body is lost for longer than `max_dropout` (nothing to bridge). When anything was cut, each
stretch that lasts `MIN_AIRBORNE` becomes a flight of its own and the shorter ones are left
out (named in the warnings); at least one must last so.

**Naming the flights.** The longest stretch keeps the take's name (`NAME.csv`: a take cut
to one stretch is named as it always was); the others follow in time order as `NAME_2`,
`NAME_3`, ... (`stretch_name`).

A take that flies throughout (fwid's own simulated takes) is never still, so nothing is cut.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from jaxtyping import Bool, Float

from .._errors import FlightDataError
from ._raw import RawTake

#: Seconds over which the position's spread is taken: several wing beats (at 4 Hz and up)
#: so the flapping ripple of a hovering vehicle counts as motion, yet well under a lift-off.
WINDOW = 0.5
#: Largest spread (m, the rms distance from the window's mean position) of a vehicle at
#: rest: the tracking noise (0.1-1 mm) is far below it, while 1 cm over 0.5 s is a mean
#: speed of only about 7 cm/s (a uniform motion at speed v spreads by v W / sqrt(12)), less
#: than any free flight of a flapping vehicle holds for half a second.
STILL = 0.01
#: Height (m) a rest may sit above the lowest one (a mat, an uneven floor, a vehicle on its
#: side), and the height above its rest the vehicle must clear to count as airborne: about a
#: wing span, the reach of the ground effect for a flapping vehicle of a few decimetres.
CLEARANCE = 0.2
#: Shortest airborne stretch (s) kept when a take is cut: several periods and time
#: constants of the slowest modes a flapping vehicle's model holds (about 1 s), and room
#: for the quiet start the trim is estimated from.
MIN_AIRBORNE = 5.0


class Airborne(NamedTuple):
    """Where a take is airborne: `keep` the samples of its longest stretch (`slice`),
    `ground` the `[start, end]` times on the ground, `others` the airborne stretches left
    out (under `MIN_AIRBORNE`), `gaps` the tracking losses the take was split at, `warnings`
    what was cut and why (one sentence each), `more` the further stretches long enough to
    be flights of their own (slices, in time order: `NAME_2`, `NAME_3`, ...)."""

    keep: slice
    ground: list[list[float]]
    others: list[list[float]]
    gaps: list[list[float]]
    warnings: list[str]
    more: list[slice] = []


def stretch_name(name: str, k: int, taken=frozenset()) -> str:
    """The name of a take's `k`-th flight (0: the longest stretch, the take's own name;
    1, 2, ...: the others in time order, `NAME_2`, `NAME_3`, ...; `NAME_stretch2`, ...
    where another take of the run is named `NAME_2`, in `taken`, so no flight overwrites
    another)."""
    if k == 0:
        return name
    return f"{name}_{k + 1}" if f"{name}_{k + 1}" not in taken else f"{name}_stretch{k + 1}"


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """The `(start, stop)` index pairs (stop exclusive) of each run of True in `mask`."""
    edges = np.diff(np.concatenate([[0], np.asarray(mask, int), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def spread(pos: Float[np.ndarray, "n 3"], tracked: Bool[np.ndarray, " n"],
           width: int) -> Float[np.ndarray, " n"]:
    """The rms distance of the tracked positions from their mean over the `width` samples
    centred on each sample (NaN where fewer than half of them are tracked)."""
    n = len(pos)
    x = np.where(tracked[:, None], pos - np.nanmean(pos[tracked], 0), 0.0)
    c = np.concatenate([[0.0], np.cumsum(tracked.astype(float))])
    s1 = np.concatenate([np.zeros((1, 3)), np.cumsum(x, 0)])
    s2 = np.concatenate([np.zeros((1, 3)), np.cumsum(x**2, 0)])
    lo = np.clip(np.arange(n) - width // 2, 0, n)
    hi = np.clip(lo + width, 0, n)
    k = c[hi] - c[lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (s1[hi] - s1[lo]) / k[:, None]
        var = np.sum((s2[hi] - s2[lo]) / k[:, None] - mean**2, 1)
    return np.where(k >= max(width // 2, 1), np.sqrt(np.maximum(var, 0.0)), np.nan)


def on_ground(t: Float[np.ndarray, " n"], pos: Float[np.ndarray, "n 3"],
              tracked: Bool[np.ndarray, " n"], f: Float[np.ndarray, " n"] | None = None):
    """`(rest, wings_off)`: the samples where the vehicle rests on the ground (still and
    low, module docstring) and those where its logged wing beat `f` is not positive
    (`pos` north-east-down, NaN where untracked)."""
    dt = float(np.median(np.diff(t)))
    still = spread(pos, tracked, max(3, int(round(WINDOW / dt)))) < STILL
    z = np.where(tracked, pos[:, 2], np.nan)
    rest = np.zeros(len(t), bool)
    if np.any(still & tracked):
        floor = float(np.max(z[still & tracked]))  # down is +z: the lowest still height
        with np.errstate(invalid="ignore"):
            rest = still & (z >= floor - CLEARANCE)
    wings_off = np.zeros(len(t), bool) if f is None else np.isfinite(f) & ~(f > 0)
    return rest, wings_off


def _clear(z, a, b, ref, first: bool):
    """The first (or last) index in `a:b` whose height (`z`, down) clears `ref` by
    `CLEARANCE` (the first or last of all when `ref` is unknown); None when none does."""
    if not np.isfinite(ref):
        return a if first else b - 1
    with np.errstate(invalid="ignore"):
        up = np.flatnonzero(ref - z[a:b] >= CLEARANCE)
    if up.size == 0:
        return None
    return a + int(up[0] if first else up[-1])


def _span(t, a, b) -> list[float]:
    return [float(t[a]), float(t[b - 1])]


def _times(spans) -> str:
    shown = ", ".join(f"{a:.6g} to {b:.6g} s" for a, b in spans[:4])
    return shown + (f" and {len(spans) - 4} more" if len(spans) > 4 else "")


def airborne(t: Float[np.ndarray, " n"], pos: Float[np.ndarray, "n 3"],
             tracked: Bool[np.ndarray, " n"], f: Float[np.ndarray, " n"] | None = None, *,
             max_dropout: float, keep_ground: bool = False, path: str = "",
             name: str = "", taken=frozenset()) -> Airborne:
    """The airborne stretch of a take to keep (module docstring).

    **Arguments:**
    - `t` (s, uniform), `pos` `(n, 3)` (m, north-east-down, NaN where untracked), `tracked`;
    - `f`: the logged flapping frequency (Hz) on `t`, or None where the take logs none;
    - `max_dropout`: the longest tracking loss (s) bridged; the take is split at longer ones;
    - `keep_ground`: keep the rests on the ground too (the wings at rest are still cut: a
      flight's `f` must be positive), and say where they are;
    - `path`: the take, for messages; `name`: its name, for the flights' names in them;
      `taken`: the names of the run's other takes (`stretch_name`).

    **Returns:** an `Airborne`. Raises a `FlightDataError` when the take is cut and no
    stretch of `MIN_AIRBORNE` is left.
    """
    n = len(t)
    dt = float(np.median(np.diff(t)))
    z = np.where(tracked, pos[:, 2], np.nan)
    rest, wings_off = on_ground(t, pos, tracked, f)
    ground = rest | wings_off
    pieces = []
    for a, b in runs(~(wings_off if keep_ground else ground)):
        if not keep_ground:
            if a > 0:  # lift-off: from where the height clears the rest before
                a = _clear(z, a, b, np.nanmedian(z[_run_before(ground, a)]), True)
            if a is not None and b < n:  # touch-down: to where it last clears the one after
                end = _clear(z, a, b, np.nanmedian(z[_run_after(ground, b)]), False)
                b = None if end is None else end + 1
            if a is None or b is None:
                continue
        pieces.append((a, b))
    lost = [(a, b) for a, b in runs(~tracked) if (b - a) * dt > max_dropout + 1e-9]
    split = []
    for a, b in pieces:
        for g0, g1 in lost:
            if a < g0 < b:
                split.append((a, g0))
                a = g1
        split.append((a, b))
    split = [(int(s[0]), int(s[-1]) + 1) for a, b in split
             if (s := np.flatnonzero(tracked[a:b]) + a).size >= 3]
    gaps = [_span(t, a, b) for a, b in lost if any(p0 < a < p1 for p0, p1 in pieces)]
    on = [_span(t, a, b) for a, b in runs(ground)]
    cut = bool(on) and not keep_ground or bool(gaps) or wings_off.any()
    if not split or (cut and max(t[b - 1] - t[a] for a, b in split) < MIN_AIRBORNE):
        raise FlightDataError(_refusal(path, t, split, on, gaps, lost, dt, max_dropout,
                                       keep_ground))
    k = max(range(len(split)), key=lambda i: t[split[i][1] - 1] - t[split[i][0]])
    a, b = split[k]
    long = [i for i, (p, q) in enumerate(split)
            if i != k and (not cut or t[q - 1] - t[p] >= MIN_AIRBORNE)]
    others = [_span(t, *s) for i, s in enumerate(split) if i != k and i not in long]
    more = [slice(*split[i]) for i in long]
    notes = []
    what = _ground_words(rest, wings_off)
    if on and keep_ground:
        notes.append(f"the vehicle is on the ground ({what}) at t = {_times(on)}; kept "
                     "(--keep-ground)" + (", but for the wings at rest: a flight's f must be "
                                          "positive" if wings_off.any() else ""))
    elif on:
        where = ("the take is cut to its airborne stretches (below)" if more else
                 f"the flight is cut to t = {t[a]:.6g} to {t[b - 1]:.6g} s")
        notes.append(f"the vehicle is on the ground ({what}) at t = {_times(on)}: {where}, "
                     f"where it is airborne "
                     f"({CLEARANCE:g} m clear of its rest height), because the floor's reaction "
                     "is no aerodynamic load (--keep-ground keeps it all)")
    why = (f"; the take is split where the body is lost for longer than the "
           f"{max_dropout:g} s bridged (t = {_times(gaps)})" if gaps else "")
    kind = "" if keep_ground else "airborne "
    short = (f"; left out, under the {MIN_AIRBORNE:g} s an identification needs: "
             f"t = {_times(others)}" if others else "")
    if more:
        name = name or "take"
        flights = ", ".join(f"t = {t[s.start]:.6g} to {t[s.stop - 1]:.6g} s "
                            f"({stretch_name(name, j, taken)}.csv)"
                            for j, s in enumerate([slice(a, b)] + more))
        notes.append(f"the take gives {len(more) + 1} flights, one per {kind}stretch long "
                     f"enough to identify (the longest keeps the take's name): "
                     f"{flights}{short}{why}")
    elif others:
        notes.append(f"the longest {kind}stretch, t = {t[a]:.6g} to {t[b - 1]:.6g} s, is "
                     f"kept; left out: t = {_times(others)}{why}")
    return Airborne(slice(a, b), on, others, gaps, notes, more)


def _ground_words(rest, wings_off) -> str:
    said = []
    if rest.any():
        said.append(f"still within {CLEARANCE:g} m of its lowest height")
    if wings_off.any():
        said.append("the wings at rest")
    return ", or ".join(said)


def _run_before(mask, a) -> slice:
    """The run of True in `mask` that ends at index `a`."""
    i = a
    while i > 0 and mask[i - 1]:
        i -= 1
    return slice(i, a)


def _run_after(mask, b) -> slice:
    """The run of True in `mask` that starts at index `b`."""
    j = b
    while j < len(mask) and mask[j]:
        j += 1
    return slice(b, j)


def _refusal(path, t, split, on, gaps, lost, dt, max_dropout, keep_ground) -> str:
    """The one line that refuses a take with no airborne stretch long enough."""
    longest = max((t[b - 1] - t[a] for a, b in split), default=0.0)
    left = (f"the longest airborne stretch lasts {longest:.3g} s, under the {MIN_AIRBORNE:g} s "
            "an identification needs" if split else "no airborne stretch is left")
    if gaps or (lost and not on):
        g0, g1 = (gaps or [_span(t, *lost[0])])[0]
        return (f"{path}: the body is lost for {g1 - g0 + dt:.3g} s from t = {g0:.6g} s to "
                f"{g1:.6g} s, longer than the {max_dropout:g} s that are bridged, and {left}; "
                "fill the gap in the tracking software, cut the take, or raise --max-dropout")
    return (f"{path}: the vehicle is on the ground (still within {CLEARANCE:g} m of its lowest "
            f"height, or the wings at rest) at t = {_times(on)} and {left}; give a take of "
            "a flight" + ("" if keep_ground else ", or --keep-ground to keep the whole record"))


def _cut(take: RawTake, f, s: slice, part: int, parts: int, name: str, warnings):
    """The take (and `f`) cut to the samples `s`, named `name`, its stretch noted."""
    lo, hi = take.t[s][0], take.t[s][-1]
    take = take._replace(
        name=name, t=take.t[s], pos=take.pos[s], quat=take.quat[s], tracked=take.tracked[s],
        controls=None if take.controls is None else {k: v[s] for k, v in take.controls.items()},
        dropouts=[g for g in take.dropouts if g[0] >= lo and g[1] <= hi],
        warnings=take.warnings + warnings,
        stretch={"t_s": [float(lo), float(hi)], "part": part, "of": parts})
    return take, (None if f is None else f[s])


def cut_take(take: RawTake, f=None, *, max_dropout: float, keep_ground: bool = False,
             taken=frozenset()):
    """`(flights, airborne)`: the take (and its flapping frequency `f` on its samples, when
    given) cut to each airborne stretch long enough to identify (`airborne`), as a list of
    `(take, f)`, the longest first (named as the take), then the others in time order
    (`NAME_2`, `NAME_3`, ...); each take's warnings are extended by the cut's, and its
    `stretch` says which part of the take it is (`part` of `of`, in time order).
    The wing beat is the take's own logged `f` (the fwid raw CSV, a map's take); a Motive
    take's log runs on a clock not yet aligned, so its pose alone tells. `taken`: the names of
    the run's other takes, which no stretch's name repeats (`stretch_name`)."""
    logged = take.controls.get("f") if take.controls is not None else None
    air = airborne(take.t, take.pos, take.tracked, logged, max_dropout=max_dropout,
                   keep_ground=keep_ground, path=take.path, name=take.name, taken=taken)
    order = sorted([air.keep] + air.more, key=lambda s: s.start)
    parts = [air.keep] + air.more
    return [_cut(take, f, s, order.index(s) + 1, len(parts), stretch_name(take.name, k, taken),
                 air.warnings) for k, s in enumerate(parts)], air
