"""The vehicle's mass and inertia against the flight's loads: a `vehicle.json` in grams or
g cm^2 is refused in one line naming the file, the key, the value and the likely unit; fwid's
own flights, and flights without load columns, pass."""

import json

import numpy as np
import pytest

from fwid import FlightDataError
from fwid.data import read_flights
from fwid.data._scale import check_vehicle_scale, scale_ratios

from .helpers import VEHICLE, lon_flight, write_flight


def _consistent(vehicle=VEHICLE):
    """A flight whose loads are the ones its states imply (rigid-body equations)."""
    c = lon_flight()
    t, g, m = c["t"], vehicle["g"], vehicle["mass"]
    d = lambda x: np.gradient(x, t)  # noqa: E731
    c["X"] = m * (d(c["u"]) + c["q"] * c["w"] + g * np.sin(c["theta"]))
    c["Z"] = m * (d(c["w"]) - c["q"] * c["u"] - g * np.cos(c["theta"]))
    c["M"] = vehicle["Iy"] * d(c["q"])
    return c


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    from fwid.synth import write_flights

    out = tmp_path_factory.mktemp("sim")
    write_flights(out, n_flights=1, seed=5, duration=2.0)
    return out


def test_consistent_constants_pass():
    c = _consistent()
    ratios = scale_ratios(c.pop("t"), c, VEHICLE)
    assert set(ratios) == {"mass", "Iy"}
    assert all(abs(r - 1) < 0.05 for r, _ in ratios.values())


def test_mass_in_grams_is_refused(tmp_path):
    path = write_flight(tmp_path, cols=_consistent(), vehicle={**VEHICLE, "mass": 18.0})
    with pytest.raises(FlightDataError) as info:
        read_flights(path)
    msg = str(info.value)
    assert msg.startswith(str(tmp_path / "vehicle.json") + ": ") and "\n" not in msg
    assert "'mass' = 18" in msg and "looks like grams" in msg and "give it in kg (0.018)" in msg
    assert "lon_0.csv" in msg and "'Iy'" not in msg


def test_inertia_in_g_cm2_is_refused():
    c = _consistent()
    t = c.pop("t")
    bad = {**VEHICLE, "Iy": VEHICLE["Iy"] * 1e7}
    with pytest.raises(FlightDataError, match=r"v\.json: 'Iy' = 150 is 1e\+07 times what the "
                                              r"loads M of f\.csv imply.*looks like g cm\^2"):
        check_vehicle_scale("v.json", "f.csv", t, c, bad)


def test_every_bad_constant_at_once():
    c = _consistent()
    t = c.pop("t")
    bad = {**VEHICLE, "mass": VEHICLE["mass"] * 1e3, "Iy": VEHICLE["Iy"] * 1e3}
    with pytest.raises(FlightDataError, match=r"'mass' = 18 .*grams.*; 'Iy' = .*g m\^2"):
        check_vehicle_scale("v.json", "f.csv", t, c, bad)


def test_flights_without_loads_pass(tmp_path):
    c = {k: v for k, v in _consistent().items() if k not in ("X", "Z", "M")}
    path = write_flight(tmp_path, cols=c, vehicle={**VEHICLE, "mass": 18.0})
    assert read_flights(path)[0].columns.keys() == c.keys() - {"t"}


def test_fwids_own_flights_pass(simulated):
    vehicle = json.loads((simulated / "vehicle.json").read_text())
    for f in sorted(simulated.glob("*.csv")):
        a = np.genfromtxt(f, delimiter=",", names=True)
        cols = {k: a[k] for k in a.dtype.names}
        ratios = scale_ratios(cols.pop("t"), cols, vehicle)
        assert {"mass", "Ix", "Iy", "Iz"} <= set(ratios)
        assert all(0.5 < r < 2 for r, _ in ratios.values()), ratios
    read_flights(simulated)
