"""Whether the vehicle's mass and inertia fit the flight: a `vehicle.json` in grams (or
g cm^2) makes every identified derivative 1000 (or 10^7) times too large, with no error.

A flight's force columns `X Y Z` [N] are the aerodynamic forces the motion implies,
`mass * (du/dt + q w - r v + g sin(theta), ...)` (the rigid-body equations in body axes),
and its moment columns `L M N` [N m] the moments the rates imply, `Iy dq/dt + (Ix - Iz) p r
+ Ixz (p^2 - r^2)`, .... Each load column is set against the load the states and the
constants of `vehicle.json` give; their ratio of scales, `sum(F F) / sum(F G)` (noise in
the differentiated states averages out of it), is 1 for constants that fit. It is judged
only where the two agree in shape (correlation at least `MIN_CORRELATION`), so that the
scale is all that differs, and only for the columns the flight has: a flight without load
columns is not judged.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._errors import FlightDataError

#: A constant whose loads are this many times too large or too small is refused: an order
#: of magnitude, beyond any error of weighing or of a reconstruction, and short of every
#: unit slip (grams, g cm^2, ...).
MAX_FACTOR = 10.0
#: The loads and the states must agree at least this well in shape to judge the scale.
MIN_CORRELATION = 0.5
#: Units a constant may have been given in, by their factor to SI (kg, kg m^2).
MASS_UNITS = {"grams": 1e-3}
INERTIA_UNITS = {"g m^2": 1e-3, "kg cm^2": 1e-4, "g cm^2": 1e-7, "kg mm^2": 1e-6,
                 "g mm^2": 1e-9}


def _implied(t, columns, v: Mapping[str, float]):
    """The loads the states and the constants `v` imply, per load column, and which
    constant scales each: `{col: (load, key)}`."""
    zero = np.zeros_like(t)
    u, w, q, th, p, r, vv, phi = (np.asarray(columns.get(c, zero), dtype=float)
                                  for c in ("u", "w", "q", "theta", "p", "r", "v", "phi"))
    d = lambda x: np.gradient(x, t)  # noqa: E731
    g, m = v["g"], v["mass"]
    Ix, Iy, Iz, Ixz = v["Ix"], v["Iy"], v["Iz"], v["Ixz"]
    return {
        "X": (m * (d(u) + q * w - r * vv + g * np.sin(th)), "mass"),
        "Y": (m * (d(vv) + r * u - p * w - g * np.cos(th) * np.sin(phi)), "mass"),
        "Z": (m * (d(w) + p * vv - q * u - g * np.cos(th) * np.cos(phi)), "mass"),
        "L": (Ix * d(p) - Ixz * d(r) + (Iz - Iy) * q * r - Ixz * p * q, "Ix"),
        "M": (Iy * d(q) + (Ix - Iz) * p * r + Ixz * (p * p - r * r), "Iy"),
        "N": (Iz * d(r) - Ixz * d(p) + (Iy - Ix) * p * q + Ixz * q * r, "Iz"),
    }


#: The states each load column needs (besides those that may be absent, taken as zero).
_NEEDS = {"X": ("u", "theta"), "Y": ("v",), "Z": ("w", "theta"), "L": ("p",), "M": ("q",),
          "N": ("r",)}


def scale_ratios(t, columns: Mapping[str, np.ndarray], vehicle: Mapping[str, float]
                 ) -> dict[str, tuple[float, list[str]]]:
    """Per constant of `vehicle` (`mass`, `Ix`, `Iy`, `Iz`), the ratio of the flight's loads
    to the loads the states and the constant imply (1 when the constant fits), and the
    load columns it was judged on; constants that cannot be judged are left out."""
    t = np.asarray(t, dtype=float)
    if t.shape[0] < 3:
        return {}
    sums: dict[str, list] = {}
    for col, (G, key) in _implied(t, columns, vehicle).items():
        if col not in columns or not all(c in columns for c in _NEEDS[col]):
            continue
        F = np.asarray(columns[col], dtype=float)
        s = sums.setdefault(key, [0.0, 0.0, 0.0, []])
        s[0] += float(F @ F)
        s[1] += float(F @ G)
        s[2] += float(G @ G)
        s[3].append(col)
    out = {}
    for key, (ff, fg, gg, cols) in sums.items():
        if ff <= 0 or gg <= 0 or fg / np.sqrt(ff * gg) < MIN_CORRELATION:
            continue
        out[key] = (ff / fg, cols)
    return out


def _unit(key: str, factor: float) -> str | None:
    """The unit that a constant `factor` times too large was likely given in."""
    units = MASS_UNITS if key == "mass" else INERTIA_UNITS
    return next((u for u, k in units.items() if abs(np.log10(factor * k)) < 0.5), None)


def check_vehicle_scale(vehicle_name: str, flight_name: str, t, columns, vehicle) -> None:
    """A [`fwid.FlightDataError`][] when a constant of `vehicle` (`mass`, `Ix`, `Iy`, `Iz`)
    is `MAX_FACTOR` times or more off what the flight's loads imply: one line naming
    `vehicle_name`, every such key, its value, the value the loads imply and the likely
    unit."""
    bad = []
    for key, (ratio, cols) in scale_ratios(t, columns, vehicle).items():
        if 1 / MAX_FACTOR < ratio < MAX_FACTOR:
            continue
        value, fit = vehicle[key], vehicle[key] * ratio
        si = "kg" if key == "mass" else "kg m^2"
        unit = _unit(key, 1 / ratio)
        how = (f"looks like {unit}: give it in {si} ({fit:.3g})" if unit
               else f"give it in {si} (or the loads {', '.join(cols)} in SI units)")
        bad.append(f"'{key}' = {value:.4g} is {_times(ratio)} what the loads "
                   f"{', '.join(cols)} of {flight_name} imply ({fit:.3g} {si}); it {how}")
    if bad:
        raise FlightDataError(f"{vehicle_name}: {'; '.join(bad)}")


def _times(ratio: float) -> str:
    return (f"{1 / ratio:.3g} times" if ratio < 1 else f"1/{ratio:.3g} of")
