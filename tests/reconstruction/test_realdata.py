"""Real recordings nobody on this project wrote (`../shared/realdata`, see its SOURCES.md):
a TU Delft Flapper Drone flight through the recording map of the guide's page on recordings.
Skipped when the folder is absent."""

from pathlib import Path

import numpy as np
import pytest

import fwid

from .helpers import REAL

FLIGHT = REAL / "fd_model_tuning_level_flight_1.csv.gz"
ALTITUDE = REAL / "fd_model_tuning_wAlt_1.csv.gz"
MAP = Path(__file__).resolve().parents[2] / "docs" / "guide" / "flapper.toml"
VEHICLE = {"mass": 0.103, "Ix": 3.2e-4, "Iy": 4.9e-4, "Iz": 3.5e-4, "Ixz": 0.0, "g": 9.81}

pytestmark = pytest.mark.skipif(not FLIGHT.exists(),
                                reason=f"real recordings not found beside the repository ({REAL})")


def test_flapper_flight_through_its_map():
    """The map as the data set's README describes it (z-up, ZYX Euler in degrees,
    accelerometer in g, forward-left-up): the accelerometer finds the logged pitch's sign
    reversed, the reconstruction's cycle-averaged specific force follows the accelerometer,
    and every state is finite and within what the vehicle flies."""
    res = fwid.reconstruct(FLIGHT, recording_map=MAP, vehicle=VEHICLE)
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


def test_both_flights_are_cut_to_where_they_fly():
    """With the default options both flights reconstruct, each cut to its airborne stretch:
    high above the floor (6-10 cm up at rest) at both ends. The altitude flight loses the
    body for 0.37 s at t = 142.5 s: its longer stretch after the loss is kept, the one
    before named."""
    res = fwid.reconstruct([FLIGHT, ALTITUDE], recording_map=MAP, vehicle=VEHICLE)
    assert not res.failures, res.failures
    level, alt = res.flights
    for fl, (lo, hi) in ((level, (55.0, 80.0)), (alt, (40.0, 80.0))):
        c = fl.columns
        assert lo < c["t"][-1] - c["t"][0] < hi, (fl.name, c["t"][[0, -1]])
        height = -c["z"]
        assert height[:50].min() > 0.25 and height[-50:].min() > 0.25, fl.name
        assert np.min(c["f"]) > 8.0, fl.name  # the motors at flight speed, not idling
        assert any("on the ground" in w and "--keep-ground" in w for w in fl.entry["warnings"])
    assert level.columns["t"][0] > 246.0 and level.columns["t"][-1] < 316.0
    assert alt.columns["t"][0] > 142.8
    assert any("left out: t = 123" in w and "142.481" in w for w in alt.entry["warnings"])


def test_keep_ground_keeps_the_whole_level_flight():
    res = fwid.reconstruct(FLIGHT, recording_map=MAP, vehicle=VEHICLE, keep_ground=True)
    assert not res.failures, res.failures
    t = res.flights[0].columns["t"]
    assert t[-1] - t[0] > 85.0
    assert any("kept (--keep-ground)" in w for w in res.flights[0].entry["warnings"])
