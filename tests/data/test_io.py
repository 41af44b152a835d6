import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid.data as fd
from fwid import FlightDataError
from fwid.data import Flight, Vehicle, load_flight, load_flights, load_vehicle

from .helpers import (
    LAT_TRIM,
    LON_TRIM,
    VEHICLE,
    lat_flight,
    lon_flight,
    write_csv,
    write_flight,
    write_json,
    write_text,
)


def test_public_api():
    for name in (
        "Flight",
        "Vehicle",
        "load_flight",
        "load_flights",
        "load_vehicle",
        "estimate_trim",
        "first_input_index",
    ):
        assert hasattr(fd, name)


# ------------------------------------------------------------------ load_flight


def test_load_flight(tmp_path):
    c = lon_flight()
    path = write_flight(tmp_path, "lon_0.csv", cols=c)
    f = load_flight(path)
    assert isinstance(f, Flight)
    assert f.name == "lon_0.csv"
    assert set(f.columns) == set(c) - {"t"}
    assert f.t.dtype == jnp.float64 and f["q"].dtype == jnp.float64
    assert f.n == 800 and f.dt == pytest.approx(0.005)
    np.testing.assert_allclose(np.asarray(f.t), c["t"], atol=1e-12)
    np.testing.assert_allclose(np.asarray(f["theta"]), c["theta"], rtol=1e-9)
    assert abs(f.first_input - 200) <= 1
    for col in ("u", "w", "theta", "q", "de"):
        assert float(f.trim[col + "0"]) == pytest.approx(LON_TRIM[col], abs=1e-3)
    # Delta quantities are ~0 over the quiet start
    assert np.max(np.abs(np.asarray(f.perturbation("theta"))[: f.first_input])) < 0.01
    assert isinstance(f.vehicle, Vehicle)
    assert f.vehicle.as_dict() == pytest.approx(VEHICLE)


def test_flight_is_a_pytree(tmp_path):
    f = load_flight(write_flight(tmp_path))

    @eqx.filter_jit
    def mean_q(flight):
        return jnp.mean(flight.perturbation("q"))

    assert np.isfinite(float(mean_q(f)))
    assert all(isinstance(x, jax.Array) for x in jax.tree_util.tree_leaves(f))


def test_lateral_flight_first_input_from_rudder(tmp_path):
    f = load_flight(write_flight(tmp_path, "lat_0.csv", cols=lat_flight(t_input=1.5)))
    assert abs(f.first_input - 300) <= 1
    for col in ("v", "p", "r", "phi", "dr"):
        assert float(f.trim[col + "0"]) == pytest.approx(LAT_TRIM[col], abs=1e-3)


def test_no_vehicle_json(tmp_path):
    f = load_flight(write_flight(tmp_path, vehicle=False))
    assert f.vehicle is None


def test_vehicle_argument(tmp_path):
    path = write_flight(tmp_path / "a", vehicle=False)
    v = Vehicle(mass=0.02, Ix=1.0, Iy=2.0, Iz=3.0)
    assert load_flight(path, vehicle=v).vehicle is v
    vpath = write_json(tmp_path / "other.json", {**VEHICLE, "mass": 0.5})
    assert float(load_flight(path, vehicle=vpath).vehicle.mass) == 0.5


def test_require(tmp_path):
    path = write_flight(tmp_path)
    assert load_flight(path, require=("q", "u", "w", "theta", "de")).n == 800
    assert load_flight(path, require="theta").n == 800  # one name, not its letters
    with pytest.raises(FlightDataError, match=r"lon_0\.csv: missing column 'p'"):
        load_flight(path, require=["q", "p"])


def test_extra_columns_are_kept(tmp_path):
    c = {**lon_flight(), "battery_V": np.full(800, 3.7)}
    f = load_flight(write_flight(tmp_path, cols=c))
    assert float(f["battery_V"][0]) == 3.7
    assert float(f.trim["battery_V0"]) == pytest.approx(3.7)


def test_tolerant_header_and_layout(tmp_path):
    # BOM, a leading comment, '# ' before the header, spaces and quotes in names, CRLF,
    # a trailing comma, comment and blank lines between rows
    c = lon_flight()
    names = list(c)
    rows = [",".join(f"{c[k][i]:.10g}" for k in names) + "," for i in range(800)]
    rows.insert(300, "# pause")
    rows.insert(500, "")
    header = "# " + ", ".join(f'"{k}"' for k in names) + ","
    path = tmp_path / "messy.csv"
    lines = ["# DelFly II flight 7", header, *rows]
    path.write_bytes(("\ufeff" + "\r\n".join(lines) + "\r\n").encode("utf-8"))
    f = load_flight(path)
    assert set(f.columns) == set(names) - {"t"}
    assert f.n == 800
    np.testing.assert_allclose(np.asarray(f["q"]), c["q"], rtol=1e-9)


def test_uniform_time_grid_is_stored(tmp_path):
    c = lon_flight(rate=300.0)
    c["t"] = np.round(c["t"] + 10.0, 5)
    f = load_flight(write_flight(tmp_path, cols=c))
    d = np.diff(np.asarray(f.t))
    assert np.ptp(d) < 1e-12 and f.dt == pytest.approx(1 / 300, rel=1e-5)
    assert float(f.t[0]) == pytest.approx(10.0)


# ------------------------------------------------------------------ sidecar


def test_sidecar_trim_overrides_estimate(tmp_path):
    path = write_flight(tmp_path, sidecar={"trim": {"u0": 0.7, "theta0": 1.3, "V0": 0.75}})
    f = load_flight(path)
    assert float(f.trim["u0"]) == 0.7
    assert float(f.trim["theta0"]) == 1.3
    assert float(f.trim["V0"]) == 0.75  # any <col>0 key
    assert float(f.trim["w0"]) == pytest.approx(LON_TRIM["w"], abs=1e-3)  # still estimated
    assert float(f.perturbation("u")[0]) == pytest.approx(LON_TRIM["u"] - 0.7, abs=0.01)


def test_sidecar_first_input(tmp_path):
    f = load_flight(write_flight(tmp_path, sidecar={"first_input": 150}))
    assert f.first_input == 150
    with pytest.raises(FlightDataError, match="'first_input' = 900 is beyond"):
        load_flight(write_flight(tmp_path, "b.csv", sidecar={"first_input": 900}))


@pytest.mark.parametrize(
    "sidecar, match",
    [
        ({"trim": {"u": 0.6}}, "trim key 'u' is not '<column>0'"),
        ({"trim": {"u0": "fast"}}, "trim value 'u0' must be a finite number"),
        ({"trim": [0.6]}, '"trim" must be an object'),
        ({"first_input": -3}, "'first_input' must be a sample index"),
    ],
)
def test_bad_sidecar(tmp_path, sidecar, match):
    with pytest.raises(FlightDataError, match=match) as info:
        load_flight(write_flight(tmp_path, "lon_2.csv", sidecar=sidecar))
    assert "lon_2.json" in str(info.value)


def test_sidecar_not_json(tmp_path):
    path = write_flight(tmp_path, "lon_2.csv")
    write_text(tmp_path / "lon_2.json", "{trim: }")
    with pytest.raises(FlightDataError, match=r"lon_2\.json: not valid JSON"):
        load_flight(path)


# ------------------------------------------------------------------ load_vehicle


def test_load_vehicle_defaults(tmp_path):
    content = {"mass": 0.02, "Ix": 1, "Iy": 2, "Iz": 3}
    v = load_vehicle(write_json(tmp_path / "vehicle.json", content))
    assert v.as_dict() == {"mass": 0.02, "Ix": 1.0, "Iy": 2.0, "Iz": 3.0, "Ixz": 0.0, "g": 9.81}
    assert v.mass.dtype == jnp.float64


@pytest.mark.parametrize(
    "content, match",
    [
        ({"mass": 0.02, "Ix": 1, "Iz": 3}, "missing key 'Iy'"),
        ({"Mass": 0.02, "Ix": 1, "Iy": 2, "Iz": 3}, "missing key 'mass'; rename 'Mass' to 'mass'"),
        ({"mass": -0.02, "Ix": 1, "Iy": 2, "Iz": 3}, "key 'mass' must be positive, got -0.02"),
        ({"mass": 0.02, "Ix": 0, "Iy": 2, "Iz": 3}, "key 'Ix' must be positive"),
        ({"mass": "heavy", "Ix": 1, "Iy": 2, "Iz": 3}, "key 'mass' must be a finite number"),
        ([1, 2, 3], "expected a JSON object"),
    ],
)
def test_bad_vehicle(tmp_path, content, match):
    path = write_json(tmp_path / "vehicle.json", content)
    with pytest.raises(FlightDataError, match=match) as info:
        load_vehicle(path)
    assert str(path) in str(info.value)


def test_every_missing_vehicle_key_at_once(tmp_path):
    path = write_json(tmp_path / "vehicle.json", {"Mass": 0.02, "Iy": 2e-5})
    with pytest.raises(FlightDataError) as info:
        load_vehicle(path)
    assert str(info.value) == (
        f"{path}: missing keys 'mass', 'Ix', 'Iz'; rename 'Mass' to 'mass' and add 'Ix', "
        """'Iz' (expected {"mass": kg, "Ix": kg m^2, "Iy": .., "Iz": .., "Ixz": .., """
        """"g": 9.81})""")


def test_bad_vehicle_found_beside_flight(tmp_path):
    path = write_flight(tmp_path, vehicle={"mass": 0.02, "Ix": 1, "Iy": 2})
    with pytest.raises(FlightDataError, match=r"vehicle\.json: missing key 'Iz'"):
        load_flight(path)


def test_vehicle_not_json_or_missing(tmp_path):
    with pytest.raises(FlightDataError, match="not valid JSON"):
        load_vehicle(write_text(tmp_path / "vehicle.json", "mass = 3"))
    with pytest.raises(FlightDataError, match="no such file"):
        load_vehicle(tmp_path / "nope" / "vehicle.json")


# ------------------------------------------------------------------ load_flights


def test_load_flights_folder_sorted(tmp_path):
    for name in ("lon_2.csv", "lon_0.csv", "lon_1.csv"):
        write_flight(tmp_path, name, sidecar={"trim": {"u0": 0.6}} if name == "lon_1.csv" else None)
    write_text(tmp_path / "notes.txt", "not a flight")
    flights = load_flights(tmp_path)
    assert [f.name for f in flights] == ["lon_0.csv", "lon_1.csv", "lon_2.csv"]
    assert all(f.vehicle is not None for f in flights)
    assert flights[0].vehicle is flights[2].vehicle  # one vehicle.json read per folder


def test_load_flights_mixed_arguments(tmp_path):
    a = write_flight(tmp_path / "a", "x.csv")
    write_flight(tmp_path / "b", "y.csv", vehicle=False)
    write_flight(tmp_path / "b", "z.csv", vehicle=False)
    flights = load_flights(tmp_path / "b", str(a))
    # named by the path below the folder the files share
    assert [f.name for f in flights] == ["b/y.csv", "b/z.csv", "a/x.csv"]
    assert flights[0].vehicle is None and flights[2].vehicle is not None
    assert [f.name for f in load_flights([a, tmp_path / "b" / "z.csv"])] == ["a/x.csv", "b/z.csv"]


def test_equal_file_names_in_two_folders_stay_apart(tmp_path):
    write_flight(tmp_path / "clean" / "test", "lon_0.csv")
    write_flight(tmp_path / "demo", "lon_0.csv")
    flights = load_flights(tmp_path / "clean" / "test", tmp_path / "demo")
    assert [f.name for f in flights] == ["clean/test/lon_0.csv", "demo/lon_0.csv"]


def test_folders_sort_numbers_by_value(tmp_path):
    for i in (10, 2, 1):
        write_flight(tmp_path, f"lon_{i}.csv", vehicle=i == 1)
    assert [f.name for f in load_flights(tmp_path)] == ["lon_1.csv", "lon_2.csv", "lon_10.csv"]


def test_load_flights_require(tmp_path):
    write_flight(tmp_path, "lon_0.csv")
    write_flight(tmp_path, "lon_1.csv", cols={k: v for k, v in lon_flight().items() if k != "q"})
    with pytest.raises(FlightDataError) as info:  # the path as given, folder included
        load_flights(tmp_path, require=("q",))
    assert str(info.value).startswith(f"{tmp_path / 'lon_1.csv'}: missing column 'q'")


def test_load_flights_errors(tmp_path):
    (tmp_path / "empty").mkdir()
    write_json(tmp_path / "empty" / "vehicle.json", VEHICLE)
    with pytest.raises(FlightDataError, match="holds no .csv flight files"):
        load_flights(tmp_path / "empty")
    with pytest.raises(FlightDataError, match="no such file or folder"):
        load_flights(tmp_path / "missing")
    with pytest.raises(FlightDataError, match="no flight files given"):
        load_flights()


def test_large_file_loads_fast(tmp_path):
    import time

    c = lon_flight(duration=30.0, rate=1000.0, shape="step")
    path = write_csv(tmp_path / "big.csv", c)
    start = time.perf_counter()
    f = load_flight(path)
    assert time.perf_counter() - start < 3.0  # ~0.2 s in practice
    assert f.n == 30000 and abs(f.first_input - 1000) <= 5
