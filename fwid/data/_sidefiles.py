"""The JSON files beside a flight's CSV, read without JAX: `vehicle.json` (mass and
inertia) and the sidecar `NAME.json` (trim values, first input), the flight-data format."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from .._errors import FlightDataError

PathLike = str | os.PathLike

VEHICLE_FILE = "vehicle.json"

_VEHICLE_KEYS = ("mass", "Ix", "Iy", "Iz", "Ixz", "g")
_VEHICLE_DEFAULTS = {"Ixz": 0.0, "g": 9.81}
_VEHICLE_SHAPE = '{"mass": kg, "Ix": kg m^2, "Iy": .., "Iz": .., "Ixz": .., "g": 9.81}'


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


def read_vehicle(path: PathLike) -> dict[str, float]:
    """Read the mass and inertia of the vehicle from `vehicle.json`, as floats by key (no
    JAX: [`fwid.data.load_vehicle`][] makes the `Vehicle` of them).

    The file holds `{"mass": kg, "Ix": kg m^2, "Iy": .., "Iz": .., "Ixz": .., "g": 9.81}`;
    `Ixz` defaults to 0 and `g` to 9.81 m/s^2. Other keys are ignored.

    **Arguments:**
    - `path`: the `vehicle.json` file.

    **Returns:** `{"mass": .., "Ix": .., "Iy": .., "Iz": .., "Ixz": .., "g": ..}`.

    Raises a [`fwid.FlightDataError`][] naming the file and the key when a key is missing,
    not a finite number, or out of range (mass, `Ix`, `Iy`, `Iz` and `g` must be positive).
    """
    path = Path(path)
    if not path.is_file():
        raise FlightDataError(f"{path}: no such file; write {_VEHICLE_SHAPE} there")
    data = _read_json(path, "vehicle file")
    if not isinstance(data, dict):
        raise FlightDataError(f"{path}: expected a JSON object {_VEHICLE_SHAPE}")
    missing = [key for key in _VEHICLE_KEYS if key not in data and key not in _VEHICLE_DEFAULTS]
    if missing:
        raise FlightDataError(f"{path}: {_missing(missing, data)}")
    values = {}
    for key in _VEHICLE_KEYS:
        if key not in data:
            values[key] = _VEHICLE_DEFAULTS[key]
            continue
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
    return values


def _missing(keys: list[str], data: dict) -> str:
    """Every missing key of `vehicle.json` in one phrase, with the fix for each: rename a key
    that differs only in case, else add it."""
    close = {k: next((d for d in data if isinstance(d, str) and d.lower() == k.lower()), None)
             for k in keys}
    renames = [f"'{c}' to '{k}'" for k, c in close.items() if c is not None]
    adds = [f"'{k}'" for k, c in close.items() if c is None]
    s = "s" if len(keys) > 1 else ""
    fixes = []
    if renames:
        fixes.append("rename " + ", ".join(renames))
    if adds:
        fixes.append(f"add {', '.join(adds)} (expected {_VEHICLE_SHAPE})")
    return f"missing key{s} {', '.join(repr(k) for k in keys)}; {' and '.join(fixes)}"


def read_sidecar(path: Path) -> tuple[dict[str, float], int | None]:
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
