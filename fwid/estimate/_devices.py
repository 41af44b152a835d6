"""Independent flights spread over the available devices (CPU cores, GPUs)."""

from __future__ import annotations

import jax
import numpy as np
from jax.sharding import Mesh


def device_count() -> int:
    """The devices of JAX's default backend (CPU devices: see `fwid/__init__.py`)."""
    return len(jax.devices())


def padded_count(n_flights: int) -> int:
    """`n_flights` rounded up to a multiple of the device count, so that every device gets
    the same number of flights (the extra ones are copies whose results are dropped)."""
    d = device_count()
    if n_flights < 2 or d < 2:
        return n_flights
    return -(-n_flights // d) * d


def flight_mesh(n_flights: int) -> Mesh | None:
    """A one-axis mesh, `"flights"`, over all devices when `n_flights` splits evenly over
    two or more of them; `None` otherwise (run on one device)."""
    d = device_count()
    if d < 2 or n_flights < 2 or n_flights % d:
        return None
    return Mesh(np.array(jax.devices()), ("flights",))
