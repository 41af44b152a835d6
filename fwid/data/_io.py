"""Reading flights (`NAME.csv`, its sidecar `NAME.json`) and `vehicle.json` from disk.

The on-disk format is the flight-data format: one CSV per flight with a header row, comma
separated, uniformly sampled; `vehicle.json` beside the CSV files.

Reading is in two steps: every file is read and checked with numpy first (`_read`), then
the `Flight` pytrees are made (`_build`, JAX). A bad file is thus answered before JAX is
imported, and `load_flights` checks every file before it builds any flight.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .._errors import FlightDataError
from ._checks import check_columns, check_flight
from ._csv import read_csv
from ._folders import flight_files, flight_names
from ._quiet import quiet_start_note
from ._scale import check_vehicle_scale
from ._sidefiles import VEHICLE_FILE, PathLike, read_sidecar, read_vehicle
from ._timebase import uniform_flight
from ._trim import estimate_trim, first_input_index, input_column
from ._window import window_rows

if TYPE_CHECKING:
    from ._flight import Flight, Vehicle


def load_vehicle(path: PathLike) -> Vehicle:
    """Read the mass and inertia of the vehicle from `vehicle.json`.

    The file holds `{"mass": kg, "Ix": kg m^2, "Iy": .., "Iz": .., "Ixz": .., "g": 9.81}`;
    `Ixz` defaults to 0 and `g` to 9.81 m/s^2. Other keys are ignored.

    **Arguments:**
    - `path`: the `vehicle.json` file.

    **Returns:** a [`fwid.data.Vehicle`][].

    Raises a [`fwid.FlightDataError`][] naming the file and the key when a key is missing,
    not a finite number, or out of range (mass, `Ix`, `Iy`, `Iz` and `g` must be positive).
    """
    from ._flight import Vehicle

    return Vehicle(**read_vehicle(path))


class FlightRecord(NamedTuple):
    """One flight read and checked, in numpy: what `_build` turns into a `Flight`."""

    t: np.ndarray
    columns: dict[str, np.ndarray]
    trim: dict[str, float]
    first: int
    vehicle: object  # a Vehicle, the dict of a vehicle.json, or None
    name: str
    path: str  # the file, as given (for messages)
    warnings: tuple[str, ...] = ()  # what reading changed or doubts, one line each


def _as_require(require) -> tuple[str, ...]:
    if isinstance(require, str):
        return (require,)
    return tuple(require)


def _vehicle_beside(path: Path) -> dict[str, float] | None:
    vpath = path.parent / VEHICLE_FILE
    return read_vehicle(vpath) if vpath.is_file() else None


def _read(path: Path, vehicle, require: tuple[str, ...], name: str | None,
          window=None) -> FlightRecord:
    """Read and check one flight with numpy (no JAX): every error `load_flight` can raise;
    with `window` (`(start, end)` s on its own `t`, None: open), the rows inside it (`_window`),
    the trim and first input found on them."""
    if path.is_dir():
        raise FlightDataError(f"{path}: is a folder, not a flight file; use load_flights")
    if not path.is_file():
        raise FlightDataError(f"{path}: no such file")
    where = str(path)  # messages name the path as given
    table, lines = read_csv(path, where, require)
    t = table.pop("t", None)
    columns = table
    if t is None:
        check_columns(where, list(columns), require)  # raises: names the missing 't'
    check_flight(where, t, columns, require, lines)
    t, columns, resampled = uniform_flight(where, t, columns)
    notes = [resampled] if resampled else []
    rows = slice(0, None)
    if window is not None:
        rows = window_rows(where, t, window)
        t, columns = t[rows], {k: v[rows] for k, v in columns.items()}
    n = t.shape[0]

    vehicle_name = str(path.parent / VEHICLE_FILE)
    if vehicle is None:
        vehicle = _vehicle_beside(path)
    elif isinstance(vehicle, (str, os.PathLike)):
        vehicle_name, vehicle = str(vehicle), read_vehicle(vehicle)
    elif not isinstance(vehicle, dict):
        vehicle_name = "the vehicle"
    if vehicle is not None:
        constants = vehicle if isinstance(vehicle, dict) else vehicle.as_dict()
        check_vehicle_scale(vehicle_name, where, t, columns, constants)

    trim_given, first_given = read_sidecar(path)
    col = input_column(columns, t)
    if first_given is not None:
        first_given = max(first_given - rows.start, 0)
        if first_given >= n:
            raise FlightDataError(
                f"{path.with_suffix('.json')}: 'first_input' = {first_given} is beyond the "
                f"flight's {n} samples; give a row index below {n}"
            )
        first = first_given
    else:
        first = first_input_index(t, columns[col]) if col is not None else None
    if col is not None and not trim_given:
        note = quiet_start_note(where, t, columns, col, first, str(path.with_suffix(".json")))
        notes += [note] if note else []
    first = 0 if first is None else first
    trim = estimate_trim(columns, t, first_input=first)
    trim.update(trim_given)
    for note in notes:
        warnings.warn(note, UserWarning, stacklevel=4)
    return FlightRecord(t, columns, trim, int(first), vehicle, name or path.name, where,
                        tuple(notes))


def _build(raw: FlightRecord) -> Flight:
    """The `Flight` pytree of a flight read by `_read` (imports JAX)."""
    import jax.numpy as jnp

    from ._flight import Flight, Vehicle

    vehicle = Vehicle(**raw.vehicle) if isinstance(raw.vehicle, dict) else raw.vehicle
    return Flight(
        t=jnp.asarray(raw.t, dtype=float),
        columns={c: jnp.asarray(x, dtype=float) for c, x in raw.columns.items()},
        trim={k: jnp.asarray(v, dtype=float) for k, v in raw.trim.items()},
        vehicle=vehicle,
        name=raw.name,
        first_input=raw.first,
    )


def load_flight(
    path: PathLike,
    *,
    vehicle: Vehicle | PathLike | None = None,
    require: Iterable[str] = (),
    name: str | None = None,
) -> Flight:
    """Read one flight: `NAME.csv`, its optional sidecar `NAME.json` and `vehicle.json`.

    The CSV has a header row and comma-separated numbers; every column but `t` goes into
    `Flight.columns` (extra columns are kept; non-numeric extra columns are dropped). The
    data are checked (see `fwid.data._checks`): any problem raises a
    [`fwid.FlightDataError`][] whose one-line message names the file, the column and the
    lines, and says how to fix it: among them a time column that is not in seconds, and a
    `vehicle.json` whose mass or inertia is 10 times or more off what the flight's load
    columns imply (grams, g cm^2). The time stamps, once checked to be uniform, are stored
    as the exact uniform grid through the first and last time stamps; time stamps that
    jitter by up to 25 % of the step are resampled onto that grid, with a `UserWarning`.
    A flight whose quiet start (before the first input) is shorter than the 0.2 s the trim
    needs warns too, unless its sidecar gives the trim.

    The first input is found with [`fwid.data.first_input_index`][] on `de` or `dr`,
    whichever varies (0 when neither does). The trim is estimated with
    [`fwid.data.estimate_trim`][]; values in the sidecar's `{"trim": {"u0": .., ..}}`
    override the estimates key by key (any `<col>0` key is allowed), and an optional
    `"first_input": index` there overrides the detected first input.

    **Arguments:**
    - `path`: the CSV file.
    - `vehicle`: a [`fwid.data.Vehicle`][] or the path of a `vehicle.json`; by default
      `vehicle.json` is looked up beside the CSV (`Flight.vehicle` is `None` if absent).
    - `require`: columns the caller needs (e.g. a model's states and inputs); a missing one
      is an error naming the column and the file.
    - `name`: the flight's name (default: the file name); error messages name the path as
      given.

    **Returns:** a [`fwid.data.Flight`][].
    """
    return _build(_read(Path(path), vehicle, _as_require(require), name))


def read_flights(*paths_or_folders: PathLike, require: Iterable[str] = (),
                 window=None) -> list[FlightRecord]:
    """Read and check the flights that `paths_or_folders` stand for, with numpy only (no
    JAX): every error [`load_flights`][] can raise, and the records [`build_flights`][]
    turns into flights. A caller that loads two sets (e.g. training and validation flights)
    reads both first, so that a bad file in either is answered before JAX is imported.
    `window`: `(start, end)` seconds on each flight's own `t` (None: an open side), the
    rows kept; the trim is estimated from the start of what is kept."""
    require = _as_require(require)
    files = flight_files(*paths_or_folders)
    vehicles: dict[Path, object] = {}
    records = []
    for f, name in zip(files, flight_names(files)):
        key = f.parent.resolve()
        if key not in vehicles:
            vehicles[key] = _vehicle_beside(f)
        records.append(_read(f, vehicles[key], require, name, window))
    return records


def build_flights(records: Iterable[FlightRecord]) -> list[Flight]:
    """The `Flight`s of records read by [`read_flights`][] (imports JAX); flights that share
    a `vehicle.json` share one `Vehicle`."""
    built: dict[int, object] = {}
    out = []
    for r in records:
        if isinstance(r.vehicle, dict):
            if id(r.vehicle) not in built:
                from ._flight import Vehicle

                built[id(r.vehicle)] = Vehicle(**r.vehicle)
            r = r._replace(vehicle=built[id(r.vehicle)])
        out.append(_build(r))
    return out


def load_flights(*paths_or_folders: PathLike, require: Iterable[str] = ()) -> list[Flight]:
    """Read several flights: each argument is a CSV file or a folder of them.

    A folder stands for all its `*.csv` files, sorted by name with numbers by value
    (`lon_2` before `lon_10`; `vehicle.json` and the
    sidecars `NAME.json` are read alongside, not as flights). Lists of paths are accepted
    too. Each flight is read as by [`fwid.data.load_flight`][], with `vehicle.json` looked
    up beside it; every file is read and checked before any flight is built (and before
    JAX is imported), so a bad file is answered at once.

    **Arguments:**
    - `*paths_or_folders`: CSV files and/or folders.
    - `require`: columns every flight must have.

    **Returns:** the flights, in the order given (folders expanded in name order), each
    named by its path relative to the folder all the files share (just the file name when
    they share one folder), so that equal file names in two folders stay apart.

    Raises a [`fwid.FlightDataError`][] when no path is given, a path does not exist, or a
    folder holds no CSV file.
    """
    return build_flights(read_flights(*paths_or_folders, require=require))
