"""Real recordings nobody on this project wrote (`../shared/realdata`, see its SOURCES.md):
a TU Delft Flapper Drone flight through the recording map of the guide's page on recordings.
Skipped when the folder is absent."""

from pathlib import Path

import numpy as np
import pytest

import fwid

from .helpers import REAL

FLIGHT = REAL / "fd_model_tuning_level_flight_1.csv.gz"
MAP = Path(__file__).resolve().parents[2] / "docs" / "guide" / "flapper.toml"
VEHICLE = {"mass": 0.103, "Ix": 3.2e-4, "Iy": 4.9e-4, "Iz": 3.5e-4, "Ixz": 0.0, "g": 9.81}

pytestmark = pytest.mark.skipif(not FLIGHT.exists(),
                                reason=f"real recordings not found beside the repository ({REAL})")


def test_flapper_flight_through_its_map():
    """The map as the data set's README describes it (z-up, ZYX Euler in degrees,
    accelerometer in g, forward-left-up): the accelerometer finds the logged pitch's sign
    reversed, the reconstruction's cycle-averaged specific force follows the accelerometer,
    and every state is finite and within what the vehicle flies."""
    res = fwid.reconstruct(FLIGHT, recording_map=MAP, vehicle=VEHICLE, max_dropout=1.0)
    assert not res.failures, res.failures
    fl = res.flights[0]
    imu = fl.entry["imu"]
    assert imu["frame"] == "z-up frame, pitch reversed, sensors FLU"
    assert imu["acc"]["x"]["corr"] > 0.8, imu
    assert any("pitch reversed" in w for w in fl.entry["warnings"])
    c = fl.columns
    for k in ("u", "v", "w", "p", "q", "r", "phi", "theta", "X", "Y", "Z", "L", "M", "N"):
        assert np.all(np.isfinite(c[k])), k
    assert np.max(np.abs(c["theta"])) < 1.0 and np.max(np.abs(c["phi"])) < 1.0
    assert 13.0 < np.median(c["f"]) < 16.0
