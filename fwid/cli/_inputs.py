"""Checks on the command line's input that need no JAX: a missing file is answered at once
(the same one line as [`fwid.load_flights`][]), and every flight is read and checked with
numpy (columns the command needs, NaN, time grid, units, vehicle.json) before JAX is
imported, so bad input exits 2 in a fraction of a second."""

from __future__ import annotations

from pathlib import Path

from .._errors import FlightDataError

#: The columns every flight needs for `fwid identify --model M`: the model's states and
#: input (`fwid.longitudinal()`, `fwid.lateral()`), the flapping frequency for the flapping
#: models (whose force columns depend on the axis, checked later).
IDENTIFY_COLUMNS = {
    "lon": ("q", "u", "w", "theta", "de"),
    "lat": ("p", "r", "v", "phi", "dr"),
    "flap": ("f",),
    "combined": ("f",),
}
#: The control each cycle-averaged model is driven by.
CONTROLS = {"lon": "de", "lat": "dr"}
#: Models whose constants (mass, inertia, g) come from `vehicle.json`.
VEHICLE_MODELS = ("lon", "lat", "combined")
#: The columns every flight needs for `fwid diagnose --axis A` (`fwid.diagnose`'s own list).
DIAGNOSE_COLUMNS = {
    "lon": ("u", "w", "q", "theta", "de", "f", "X", "Z", "M"),
    "lat": ("v", "p", "r", "phi", "dr", "f", "Y", "L", "N"),
}


def check_paths(*groups) -> None:
    """Every path in the lists `groups` exists, else a `FlightDataError` naming it."""
    for p in (p for group in groups for p in group or ()):
        if not Path(p).exists():
            raise FlightDataError(f"{p}: no such file or folder")


def check_controls(records, model: str) -> None:
    """A `FlightDataError` when no flight carries the control that drives `model` (the
    column is absent, or it never moves): there is nothing to identify the model's response
    from. A flight without the column while others have it is named alone."""
    import numpy as np

    control = CONTROLS.get(model)
    if control is None or not records:
        return
    lacking = [r.path for r in records if control not in r.columns]
    if len(lacking) == len(records):
        raise FlightDataError(
            f"the flights carry no controls (no {control!r} column in {', '.join(lacking)}): "
            f"the {model} model is identified from the response to {control}; add the column "
            "(e.g. from the autopilot's log)")
    if lacking:
        raise FlightDataError(f"{lacking[0]}: missing column {control!r}, the control the "
                              f"{model} model is driven by")
    still = [r for r in records if np.ptp(r.columns[control]) == 0]
    if len(still) == len(records):
        value = float(records[0].columns[control][0])
        raise FlightDataError(
            f"the flights carry no controls: {control!r} never moves in "
            f"{', '.join(r.path for r in still)} (constant {value:.4g}); there is no "
            f"manoeuvre to identify the {model} model from; use flights with a doublet or "
            "3211 input")


def window_of(args):
    """`--window START:END` read (`fwid.data._window.parse_window`), or None without it."""
    text = getattr(args, "window", None)
    if text is None:  # (no import: bad paths are answered before numpy is loaded)
        return None
    from ..data._window import parse_window

    return parse_window(text)


def read_sets(*groups, require=(), vehicle_for: str | None = None, window=None) -> list[list]:
    """Read and check every flight of each group (a list of CSV files or folders; empty:
    none) with numpy, before JAX is imported: [`fwid.data.read_flights`][] per group (each
    flight cut to `window`, `(start, end)` s on its own `t`), and, with `vehicle_for` (a
    model name), a `vehicle.json` beside every flight.

    **Returns:** the groups' records, for [`fwid.data.build_flights`][].
    """
    from ..data import read_flights

    sets = [read_flights(*group, require=require, window=window) if group else []
            for group in groups]
    for r in (r for records in sets for r in records):
        if vehicle_for and r.vehicle is None:
            raise FlightDataError(
                f"{r.path}: the {vehicle_for} model needs the vehicle's mass and inertia but "
                "no vehicle.json was found beside the flight; add one (the guide's 'Formats "
                "and interfaces' page, docs/reference/formats.md)")
    return sets
