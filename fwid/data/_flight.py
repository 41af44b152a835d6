"""The `Flight` and `Vehicle` pytrees: one flight's measured time histories, as on disk."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._errors import FlightDataError


class Vehicle(eqx.Module):
    """Mass and inertia of the vehicle (`vehicle.json`, the flight-data format).

    **Arguments:** `mass` [kg], `Ix`, `Iy`, `Iz`, `Ixz` [kg m^2], `g` [m/s^2].
    """

    mass: Float[Array, ""]
    Ix: Float[Array, ""]
    Iy: Float[Array, ""]
    Iz: Float[Array, ""]
    Ixz: Float[Array, ""]
    g: Float[Array, ""]

    def __init__(self, mass, Ix, Iy, Iz, Ixz=0.0, g=9.81):
        self.mass = jnp.asarray(mass, dtype=float)
        self.Ix = jnp.asarray(Ix, dtype=float)
        self.Iy = jnp.asarray(Iy, dtype=float)
        self.Iz = jnp.asarray(Iz, dtype=float)
        self.Ixz = jnp.asarray(Ixz, dtype=float)
        self.g = jnp.asarray(g, dtype=float)

    def as_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in ("mass", "Ix", "Iy", "Iz", "Ixz", "g")}


class Flight(eqx.Module):
    """One flight: uniformly sampled, absolute (not perturbation) time histories.

    **Fields:**
    - `t`: time [s], strictly increasing with a uniform step.
    - `columns`: every numeric column of the file but `t`, by name, in the file's SI units.
    - `trim`: the linearisation point (`u0`, `w0`, `theta0`, and `<col>0` for every other
      column), estimated from the quiet start or read from the sidecar `NAME.json`.
    - `vehicle`: mass and inertia, or `None` when no `vehicle.json` was found.
    - `name`: the file name (static), used in every message about this flight.
    - `first_input`: index of the first sample of the manoeuvre (static).
    """

    t: Float[Array, " n"]
    columns: dict[str, Float[Array, " n"]]
    trim: dict[str, Float[Array, ""]]
    vehicle: Vehicle | None
    name: str = eqx.field(static=True)
    first_input: int = eqx.field(static=True, default=0)

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def __contains__(self, col: str) -> bool:
        return col == "t" or col in self.columns

    def __getitem__(self, col: str) -> Float[Array, " n"]:
        if col == "t":
            return self.t
        try:
            return self.columns[col]
        except KeyError:
            raise FlightDataError(
                f"{self.name}: missing column '{col}' (has: {', '.join(sorted(self.columns))})"
            ) from None

    def perturbation(self, col: str) -> Float[Array, " n"]:
        """`col` minus its trim value: the paper's Delta quantities (Eqs. 1-9)."""
        return self[col] - self.trim_value(col)

    def trim_value(self, col: str) -> Float[Array, ""]:
        key = col + "0"
        if key in self.trim:
            return self.trim[key]
        return jnp.asarray(0.0)

    def require(self, cols) -> None:
        """Raise a `FlightDataError` naming the first of `cols` the flight lacks."""
        missing = [c for c in cols if c not in self]
        if missing:
            raise FlightDataError(
                f"{self.name}: missing column{'s' if len(missing) > 1 else ''} "
                f"{', '.join(repr(c) for c in missing)} needed by this model "
                f"(has: {', '.join(sorted(self.columns))})"
            )

    def with_columns(self, **cols) -> "Flight":
        """A copy with some columns replaced or added (e.g. filtered versions)."""
        new = dict(self.columns)
        new.update({k: jnp.asarray(v) for k, v in cols.items()})
        return eqx.tree_at(lambda f: f.columns, self, new)

    def slice(self, start: int, stop: int | None = None) -> "Flight":
        """Samples `start:stop` (time not re-based); trim is kept."""
        sl = np.s_[start:stop]
        return Flight(
            t=self.t[sl],
            columns={k: v[sl] for k, v in self.columns.items()},
            trim=self.trim,
            vehicle=self.vehicle,
            name=self.name,
            first_input=max(0, self.first_input - start),
        )
