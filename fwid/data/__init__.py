"""Flight data: reading, checking and trimming the flights of the flight-data format.

`import fwid.data` imports no JAX: the loader reads and checks every file with numpy, so a
bad file is answered before JAX is imported; `Flight` and `Vehicle` (equinox pytrees) are
imported on first use.
"""

from ._io import (
    FlightRecord as FlightRecord,
    build_flights as build_flights,
    load_flight as load_flight,
    load_flights as load_flights,
    load_vehicle as load_vehicle,
    read_flights as read_flights,
)
from ._trim import (
    estimate_trim as estimate_trim,
    first_input_index as first_input_index,
)

__all__ = ["Flight", "FlightRecord", "Vehicle", "build_flights", "estimate_trim",
           "first_input_index", "load_flight", "load_flights", "load_vehicle", "read_flights"]


def __getattr__(name):
    if name in ("Flight", "Vehicle"):
        from . import _flight

        return getattr(_flight, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
