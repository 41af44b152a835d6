"""Flight data: reading, checking and trimming the flights of CONTRACTS section 1."""

from ._flight import Flight as Flight, Vehicle as Vehicle
from ._io import (
    load_flight as load_flight,
    load_flights as load_flights,
    load_vehicle as load_vehicle,
)
from ._trim import (
    estimate_trim as estimate_trim,
    first_input_index as first_input_index,
)
