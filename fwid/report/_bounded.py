"""What a number can be: whether a parameter is identifiable from the flights, and whether (and
when) a simulation diverged from the data. The one place these are decided; the terminal
summary, `report.json`, `parameters.csv` and the figures all ask here, so a standard
deviation of 1e43 prints as "not identifiable from these flights" and an RMS of 1e20 as
"diverged at t = ... s", while `report.json` keeps the raw numbers beside the verdicts.
"""

from __future__ import annotations

import math

import numpy as np

#: A parameter whose standard deviation exceeds its value this many times is not identifiable.
STD_OVER_VALUE_MAX = 1e3
#: A simulated output further outside the measured range than this many times that range has
#: diverged (a fit's simulation that merely misses stays within a few ranges).
DIVERGED_RANGES = 100.0
#: The words of a parameter that is not identifiable.
NOT_IDENTIFIABLE = "not identifiable from these flights"


def identifiable(value, std) -> bool | None:
    """Whether a parameter with estimate `value` and standard deviation `std` is identifiable
    from the flights: `False` when either is not finite or `std` exceeds
    [`STD_OVER_VALUE_MAX`][] times `|value|`; `None` when `std` is not known (`None`)."""
    if std is None:
        return None
    value, std = float("nan") if value is None else float(value), float(std)
    if not (math.isfinite(value) and math.isfinite(std)):
        return False
    return abs(std) <= STD_OVER_VALUE_MAX * abs(value)


def diverged_at(t, measured, simulated, ranges: float = DIVERGED_RANGES) -> float | None:
    """The first time `t` at which `simulated` is not finite or lies more than `ranges` times
    the measured range outside it (`None` when it never does)."""
    z, y = np.asarray(measured, float), np.asarray(simulated, float)
    finite = z[np.isfinite(z)]
    if finite.size == 0:
        return None
    lo, hi = float(finite.min()), float(finite.max())
    span = max(hi - lo, 1e-12 * max(abs(lo), abs(hi), 1.0))
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(y) | (y > hi + ranges * span) | (y < lo - ranges * span)
    return float(np.asarray(t, float)[np.argmax(bad)]) if bad.any() else None


def flight_divergence(flight_fit) -> dict[str, float]:
    """`{signal: t}`: when each of a [`fwid.FlightFit`][]'s simulated outputs and loads
    diverged ([`diverged_at`][]); the signals that did not are left out."""
    out = {}
    for meas, sim in ((flight_fit.measured, flight_fit.simulated),
                      (flight_fit.forces_measured, flight_fit.forces_simulated)):
        for k in meas:
            if k in sim:
                t = diverged_at(flight_fit.t, meas[k], sim[k])
                if t is not None:
                    out[k] = t
    return out


def mark_diverged(metrics: dict, flight_fits) -> dict:
    """`metrics` (`{signal: {corr, r2, rms, rms_pct}}` of `flight_fits`, pooled or of one
    flight) with `diverged_at_s` (the earliest time any flight's simulation of the signal
    diverged, on that flight's own `t`) and `diverged_in` (that flight) added where one did."""
    first: dict[str, tuple[float, str]] = {}
    for ff in flight_fits:
        for k, t in flight_divergence(ff).items():
            if k not in first:
                first[k] = (t, ff.name)
    return {k: ({**m, "diverged_at_s": first[k][0], "diverged_in": first[k][1]}
                if k in first else m) for k, m in metrics.items()}


def with_identifiable(params: dict) -> dict:
    """A report's parameter table (`{name: {value, std, ...}}`) with `identifiable`
    ([`identifiable`][]) added to each entry."""
    return {k: {**p, "identifiable": identifiable(p.get("value"), p.get("std"))}
            for k, p in params.items()}


def axis_limits(measured, margin: float = 0.25) -> tuple[float, float] | None:
    """The y range a panel keeps: the measured range widened by `margin` of it on each side
    (`None` when nothing measured is finite)."""
    z = np.asarray(measured, float)
    z = z[np.isfinite(z)]
    if z.size == 0:
        return None
    lo, hi = float(z.min()), float(z.max())
    pad = margin * (hi - lo) if hi > lo else max(abs(hi), 1.0) * margin
    return lo - pad, hi + pad


def drawable(t, measured, simulated) -> np.ndarray:
    """`simulated` as a figure draws it: up to where it diverged ([`diverged_at`][]; NaN,
    not drawn, from there on), non-finite values left out and the rest held within ten
    measured ranges of the measured range (beyond the axis [`clip_to_measured`][] keeps, so
    the curve looks the same, and no transform overflows)."""
    y = np.asarray(simulated, float)
    lim = axis_limits(measured)
    if lim is None:
        return np.full_like(y, np.nan)
    lo, hi = lim
    at = diverged_at(t, measured, simulated)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(y) & (np.asarray(t, float) < (np.inf if at is None else at))
        return np.where(keep, np.clip(y, lo - 10 * (hi - lo), hi + 10 * (hi - lo)), np.nan)


def clip_to_measured(ax, t, measured, simulated, residual_ax=None) -> float | None:
    """Keep a figure panel's y axis to the measured range ([`axis_limits`][]) when the
    simulated curve leaves it far behind, and mark where it diverged ([`diverged_at`][]):
    a dotted vertical line and a label; `residual_ax` (the panel of measured - simulated
    below it) is kept to plus or minus the measured range then. Returns that time (`None`
    when it did not)."""
    at = diverged_at(t, measured, simulated)
    lim = axis_limits(measured)
    if lim is None:
        return at
    y = np.asarray(simulated, float)
    lo, hi = lim
    if at is not None or not np.all(np.isfinite(y)) or np.nanmax(y, initial=lo) > hi + (hi - lo) \
            or np.nanmin(y, initial=hi) < lo - (hi - lo):
        ax.set_ylim(lo, hi)
    if at is not None:
        if residual_ax is not None:
            residual_ax.set_ylim(-(hi - lo), hi - lo)
            residual_ax.axvline(at, color="C3", lw=0.8, ls=":")
        ax.axvline(at, color="C3", lw=0.8, ls=":")
        ax.text(at, hi, f" diverged at t = {at:.3g} s", color="C3", fontsize=6, ha="left",
                va="top", clip_on=True)
    return at
