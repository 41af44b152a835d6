"""Reading flights (`NAME.csv`, its sidecar `NAME.json`) and `vehicle.json` from disk.

The on-disk format is CONTRACTS section 1: one CSV per flight with a header row, comma
separated, uniformly sampled; `vehicle.json` beside the CSV files.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterable, Sequence
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from .._errors import FlightDataError
from ._checks import check_columns, check_flight
from ._csv import read_csv
from ._flight import Flight, Vehicle
from ._trim import estimate_trim, first_input_index, input_column

PathLike = str | os.PathLike

VEHICLE_FILE = "vehicle.json"

_VEHICLE_KEYS = ("mass", "Ix", "Iy", "Iz", "Ixz", "g")
_VEHICLE_DEFAULTS = {"Ixz": 0.0, "g": 9.81}
_VEHICLE_SHAPE = '{"mass": kg, "Ix": kg m^2, "Iy": .., "Iz": .., "Ixz": .., "g": 9.81}'


# --------------------------------------------------------------------------- vehicle.json


def _read_json(path: Path, what: str) -> object:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as e:
        raise FlightDataError(f"{path}: cannot read {what} ({e.strerror or e})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise FlightDataError(
            f"{path}: not valid JSON ({e.msg} at line {e.lineno}, column {e.colno}); "
            f"fix the {what}"
        ) from None


def _number(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    value = float(value)
    return value if math.isfinite(value) else None


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
    path = Path(path)
    if not path.is_file():
        raise FlightDataError(f"{path}: no such file; write {_VEHICLE_SHAPE} there")
    data = _read_json(path, "vehicle file")
    if not isinstance(data, dict):
        raise FlightDataError(f"{path}: expected a JSON object {_VEHICLE_SHAPE}")
    values = {}
    for key in _VEHICLE_KEYS:
        if key not in data:
            if key in _VEHICLE_DEFAULTS:
                values[key] = _VEHICLE_DEFAULTS[key]
                continue
            close = [k for k in data if isinstance(k, str) and k.lower() == key.lower()]
            fix = (
                f"rename '{close[0]}' to '{key}'"
                if close
                else f"add it (expected {_VEHICLE_SHAPE})"
            )
            raise FlightDataError(f"{path}: missing key '{key}'; {fix}")
        value = _number(data[key])
        if value is None:
            raise FlightDataError(
                f"{path}: key '{key}' must be a finite number, got {data[key]!r}"
            )
        if key != "Ixz" and value <= 0:
            unit = {"mass": "kg", "g": "m/s^2"}.get(key, "kg m^2")
            raise FlightDataError(
                f"{path}: key '{key}' must be positive, got {value:g}; give it in {unit}"
            )
        values[key] = value
    return Vehicle(**values)


# --------------------------------------------------------------------------- CSV


# --------------------------------------------------------------------------- sidecar


def _read_sidecar(path: Path) -> tuple[dict[str, float], int | None]:
    """The trim values and first-input index given by the sidecar `NAME.json`, if any."""
    side = path.with_suffix(".json")
    if side.name == VEHICLE_FILE or not side.is_file():
        return {}, None
    data = _read_json(side, "sidecar")
    if not isinstance(data, dict):
        raise FlightDataError(f'{side}: expected a JSON object such as {{"trim": {{"u0": ..}}}}')
    trim_in = data.get("trim", {})
    if not isinstance(trim_in, dict):
        raise FlightDataError(
            f'{side}: "trim" must be an object such as {{"u0": .., "w0": .., "theta0": ..}}'
        )
    trim = {}
    for key, value in trim_in.items():
        if not (isinstance(key, str) and len(key) > 1 and key.endswith("0")):
            raise FlightDataError(
                f"{side}: trim key {key!r} is not '<column>0' (e.g. 'u0', 'theta0'); rename it"
            )
        v = _number(value)
        if v is None:
            raise FlightDataError(
                f"{side}: trim value '{key}' must be a finite number, got {value!r}"
            )
        trim[key] = v
    first = data.get("first_input")
    if first is not None and (isinstance(first, bool) or not isinstance(first, int) or first < 0):
        raise FlightDataError(
            f"{side}: 'first_input' must be a sample index (an integer >= 0), got {first!r}"
        )
    return trim, first


# --------------------------------------------------------------------------- flights


def _as_require(require) -> tuple[str, ...]:
    if isinstance(require, str):
        return (require,)
    return tuple(require)


def _vehicle_beside(path: Path) -> Vehicle | None:
    vpath = path.parent / VEHICLE_FILE
    return load_vehicle(vpath) if vpath.is_file() else None


def load_flight(
    path: PathLike,
    *,
    vehicle: Vehicle | PathLike | None = None,
    require: Iterable[str] = (),
    name: str | None = None,
) -> Flight:
    """Read one flight: `NAME.csv`, its optional sidecar `NAME.json`, and the `vehicle.json`
    beside it.

    The CSV has a header row and comma-separated numbers; every column but `t` goes into
    `Flight.columns` (extra columns are kept; non-numeric extra columns are dropped). The
    data are checked (see `fwid.data._checks`): any problem raises a
    [`fwid.FlightDataError`][] whose one-line message names the file, the column and the
    rows, and says how to fix it. The time stamps, once checked to be uniform, are stored
    as the exact uniform grid through the first and last time stamps.

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
    path = Path(path)
    require = _as_require(require)
    if path.is_dir():
        raise FlightDataError(f"{path}: is a folder, not a flight file; use load_flights")
    if not path.is_file():
        raise FlightDataError(f"{path}: no such file")
    name = name or path.name
    where = str(path)  # messages name the path as given
    table, lines = read_csv(path, where, require)
    t = table.pop("t", None)
    columns = table
    if t is None:
        check_columns(where, list(columns), require)  # raises: names the missing 't'
    check_flight(where, t, columns, require, lines)
    n = t.shape[0]
    t = t[0] + np.arange(n) * ((t[-1] - t[0]) / (n - 1))

    if vehicle is None:
        vehicle = _vehicle_beside(path)
    elif not isinstance(vehicle, Vehicle):
        vehicle = load_vehicle(vehicle)

    trim_given, first_given = _read_sidecar(path)
    if first_given is not None:
        if first_given >= n:
            raise FlightDataError(
                f"{path.with_suffix('.json')}: 'first_input' = {first_given} is beyond the "
                f"flight's {n} samples; give a row index below {n}"
            )
        first = first_given
    else:
        col = input_column(columns, t)
        first = first_input_index(t, columns[col]) if col is not None else None
        first = 0 if first is None else first
    trim = estimate_trim(columns, t, first_input=first)
    trim.update(trim_given)

    return Flight(
        t=jnp.asarray(t, dtype=float),
        columns={c: jnp.asarray(x, dtype=float) for c, x in columns.items()},
        trim={k: jnp.asarray(v, dtype=float) for k, v in trim.items()},
        vehicle=vehicle,
        name=name,
        first_input=int(first),
    )


def _flatten(items) -> list:
    out = []
    for it in items:
        if isinstance(it, (list, tuple)):
            out.extend(_flatten(it))
        else:
            out.append(it)
    return out


def natural_key(name: str) -> list:
    """Sort key that orders numbers by value: `lon_2` before `lon_10`."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def _csv_files(folder: Path) -> list[Path]:
    return sorted(
        (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() == ".csv"),
        key=lambda p: natural_key(p.name),
    )


def flight_names(files: Sequence[Path]) -> list[str]:
    """Names that tell the flights apart: each file's path relative to the folder the files
    have in common (`lon_0.csv` for one folder, `clean/lon_0.csv` and `demo/lon_0.csv` for
    two), in `/` form."""
    parents = [str(f.resolve().parent) for f in files]
    root = Path(os.path.commonpath(parents)) if parents else Path(".")
    return [f.resolve().relative_to(root).as_posix() for f in files]


def load_flights(*paths_or_folders: PathLike, require: Iterable[str] = ()) -> list[Flight]:
    """Read several flights: each argument is a CSV file or a folder of them.

    A folder stands for all its `*.csv` files, sorted by name with numbers by value
    (`lon_2` before `lon_10`; `vehicle.json` and the
    sidecars `NAME.json` are read alongside, not as flights). Lists of paths are accepted
    too. Each flight is read with [`fwid.data.load_flight`][], with `vehicle.json` looked
    up beside it.

    **Arguments:**
    - `*paths_or_folders`: CSV files and/or folders.
    - `require`: columns every flight must have.

    **Returns:** the flights, in the order given (folders expanded in name order), each
    named by its path relative to the folder all the files share (just the file name when
    they share one folder), so that equal file names in two folders stay apart.

    Raises a [`fwid.FlightDataError`][] when no path is given, a path does not exist, or a
    folder holds no CSV file.
    """
    require = _as_require(require)
    items = _flatten(paths_or_folders)
    if not items:
        raise FlightDataError("no flight files given; pass CSV files or folders of them")
    files: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = _csv_files(p)
            if not found:
                raise FlightDataError(
                    f"{p}: folder holds no .csv flight files; point to the folder with the "
                    "flights"
                )
            files.extend(found)
        elif p.is_file():
            files.append(p)
        else:
            raise FlightDataError(f"{p}: no such file or folder")
    vehicles: dict[Path, Vehicle | None] = {}
    flights = []
    for f, name in zip(files, flight_names(files)):
        key = f.parent.resolve()
        if key not in vehicles:
            vehicles[key] = _vehicle_beside(f)
        flights.append(load_flight(f, vehicle=vehicles[key], require=require, name=name))
    return flights
