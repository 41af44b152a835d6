"""A take's length unit: the header's, or, where the header names none, inferred from the
positions themselves.

The rule: a tracking room holds its bodies within `ROOM_M` metres of its origin, and a flight
reaches at least `REACH_M` from it. Positions whose largest distance from the origin `L` is at
most `ROOM_M` are metres (in millimetres the body would never leave a ball of 3 cm about the
origin); those with `1000 REACH_M <= L <= 1000 ROOM_M` are millimetres (in metres they would
lie beyond any room). The two ranges do not overlap; numbers in neither are refused.
"""

from __future__ import annotations

import numpy as np

from .._errors import FlightDataError

#: Metres per unit of the length units a header may name.
UNITS = {"millimeters": 1e-3, "centimeters": 1e-2, "meters": 1.0}
#: No tracking room holds a body farther than this from its origin (m).
ROOM_M = 30.0
#: A flight reaches at least this far from the room's origin (m).
REACH_M = 0.1


def length_unit(named: str | None, pos: np.ndarray, path: str,
                key: str = "Length Units") -> tuple[float, str, list[str]]:
    """`(metres per unit, unit name, warnings)` of positions `pos` `(n, 3)` as recorded.

    `named`: the header's unit (`Millimeters`, `Centimeters`, `Meters`), or None, and then
    the unit is inferred (module docstring) and said in the warnings. An unknown unit, or
    numbers that fit neither metres nor millimetres, is a `FlightDataError` naming `key`.
    """
    if named is not None:
        if named.lower() not in UNITS:
            raise FlightDataError(f"{path}: {key} {named!r} unknown; re-export in Millimeters "
                                  "or Meters")
        return UNITS[named.lower()], named, []
    r = np.linalg.norm(pos, axis=1)
    r = r[np.isfinite(r)]
    reach = float(r.max()) if r.size else 0.0
    if reach <= ROOM_M:
        unit, why = "Meters", (f"in millimetres the body would stay within {reach:.3g} mm of "
                               "the origin")
    elif 1e3 * REACH_M <= reach <= 1e3 * ROOM_M:
        unit, why = "Millimeters", (f"in metres the body would be {reach:.4g} m from the "
                                    "origin, beyond any tracking room")
    else:
        raise FlightDataError(
            f"{path}: the header names no {key}, and the positions (up to {reach:.4g} from the "
            "origin) fit neither metres nor millimetres; re-export the take with its header "
            f"(Motive writes {key} there), or convert the positions to metres")
    return UNITS[unit.lower()], unit, [
        f"the header names no {key}: positions read as {unit.lower()} (they reach {reach:.4g} "
        f"from the origin; {why})"]
