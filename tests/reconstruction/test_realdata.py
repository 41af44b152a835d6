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
    body for 0.37 s at t = 142.5 s: its longer stretch after the loss keeps the take's name,
    the one before (about 19 s) is a second flight, `NAME_2`."""
    res = fwid.reconstruct([FLIGHT, ALTITUDE], recording_map=MAP, vehicle=VEHICLE)
    assert not res.failures, res.failures
    level, alt, alt2 = res.flights
    assert alt2.name == alt.name + "_2" and alt2.entry["flight"] == alt.name + "_2.csv"
    t2 = alt2.columns["t"]
    assert 123.0 < t2[0] < 124.5 and 142.0 < t2[-1] < 142.6 and 17.0 < t2[-1] - t2[0] < 20.0
    assert alt2.entry["stretch"]["part"] == 1 and alt.entry["stretch"]["part"] == 2
    assert alt.entry["stretch"]["of"] == 2 and np.min(alt2.columns["f"]) > 8.0
    for fl, (lo, hi) in ((level, (55.0, 80.0)), (alt, (40.0, 80.0))):
        c = fl.columns
        assert lo < c["t"][-1] - c["t"][0] < hi, (fl.name, c["t"][[0, -1]])
        height = -c["z"]
        assert height[:50].min() > 0.25 and height[-50:].min() > 0.25, fl.name
        assert np.min(c["f"]) > 8.0, fl.name  # the motors at flight speed, not idling
        assert any("on the ground" in w and "--keep-ground" in w for w in fl.entry["warnings"])
    assert level.columns["t"][0] > 246.0 and level.columns["t"][-1] < 316.0
    assert alt.columns["t"][0] > 142.8
    assert any("gives 2 flights" in w and "142.471 s (fd_model_tuning_wAlt_1_2.csv)" in w
               for w in alt2.entry["warnings"])


def test_keep_ground_keeps_the_whole_level_flight():
    res = fwid.reconstruct(FLIGHT, recording_map=MAP, vehicle=VEHICLE, keep_ground=True)
    assert not res.failures, res.failures
    t = res.flights[0].columns["t"]
    assert t[-1] - t[0] > 85.0
    assert any("kept (--keep-ground)" in w for w in res.flights[0].entry["warnings"])


def test_the_command_writes_and_lists_each_flight_of_the_altitude_take(tmp_path, capsys):
    """`fwid reconstruct` on the altitude flight: NAME.csv and NAME_2.csv, each in
    reconstruction.json with its stretch, each on the summary lines."""
    import json

    from fwid.cli import main

    (tmp_path / "vehicle.json").write_text(json.dumps(VEHICLE))
    take = tmp_path / ALTITUDE.name
    take.symlink_to(ALTITUDE)
    rc = main(["reconstruct", str(take), "--map", str(MAP), "--out", str(tmp_path / "out"),
               "--no-figures"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    assert "fd_model_tuning_wAlt_1: 4640 samples" in cap.err
    assert "fd_model_tuning_wAlt_1_2: 1890 samples" in cap.err
    assert "reconstructed 1 of 1 takes (2 flights)" in cap.out
    entries = json.loads((tmp_path / "out" / "reconstruction.json").read_text())["flights"]
    assert [e["flight"] for e in entries] == ["fd_model_tuning_wAlt_1.csv",
                                              "fd_model_tuning_wAlt_1_2.csv"]
    assert [e["stretch"]["part"] for e in entries] == [2, 1]
    assert (tmp_path / "out" / "fd_model_tuning_wAlt_1_2.csv").is_file()
