"""Writing flights to disk per docs/reference/formats.md."""

import json

import numpy as np
import pytest

from fwid.synth import ALL_PARAMS, COLUMNS, DELFLY, INPUT_CYCLE, simulate_flight, write_flights

CONTRACT_COLUMNS = [
    "t", "q", "u", "w", "theta", "p", "r", "v", "phi", "psi",
    "de", "dr", "f", "X", "Y", "Z", "L", "M", "N",
]  # fmt: skip


def read_csv(path):
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return header, {c: data[:, i] for i, c in enumerate(header)}


@pytest.fixture(scope="module")
def lon_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("lon")
    paths = write_flights(out, n_flights=4, axis="lon", seed=7)
    return out, paths


def test_files_and_columns(lon_dir):
    out, paths = lon_dir
    assert [p.name for p in paths] == [f"lon_{i}.csv" for i in range(4)]
    assert (out / "vehicle.json").is_file()
    for p in paths:
        assert p.with_suffix(".json").is_file()
        header, cols = read_csv(p)
        assert header == CONTRACT_COLUMNS == list(COLUMNS)
        t = cols["t"]
        assert np.all(np.diff(t) > 0)
        np.testing.assert_allclose(np.diff(t), 1 / 200.0, rtol=1e-9)
        assert all(np.all(np.isfinite(v)) for v in cols.values())
        # absolute values: theta near the trim pitch attitude, u, w near trim speeds
        assert abs(np.median(cols["theta"]) - DELFLY.theta0) < 0.2
        assert abs(np.median(cols["w"]) - DELFLY.w0) < 0.2
        assert abs(np.median(cols["f"]) - 12.5) < 0.5


def test_vehicle_json(lon_dir):
    out, _ = lon_dir
    v = json.loads((out / "vehicle.json").read_text())
    assert set(v) == {"mass", "Ix", "Iy", "Iz", "Ixz", "g"}
    assert v["mass"] == DELFLY.mass and v["Iy"] == DELFLY.Iy and v["g"] == 9.81


def test_sidecar(lon_dir):
    _, paths = lon_dir
    types = []
    for p in paths:
        side = json.loads(p.with_suffix(".json").read_text())
        trim = side["trim"]
        assert all(k.endswith("0") for k in trim)
        assert trim["u0"] == DELFLY.u0 and trim["w0"] == DELFLY.w0
        assert trim["theta0"] == DELFLY.theta0
        truth = side["truth"]
        assert set(truth["parameters"]) == set(ALL_PARAMS)
        assert truth["parameters"]["Mq"] == -1.03e-3
        assert truth["effect"] == "none" and truth["strength"] == 1.0
        assert isinstance(side["first_input"], int)
        _, cols = read_csv(p)
        k0 = side["first_input"]
        assert cols["t"][k0] == pytest.approx(truth["input"]["start"], abs=0.005)
        types.append(truth["input"]["type"])
    assert types == list(INPUT_CYCLE)  # input type varies per flight
    amps = [
        json.loads(p.with_suffix(".json").read_text())["truth"]["input"]["amplitude"] for p in paths
    ]
    assert len(set(amps)) == len(amps)


def test_deterministic_by_seed(tmp_path, lon_dir):
    _, paths = lon_dir
    again = write_flights(tmp_path / "a", n_flights=2, axis="lon", seed=7)
    other = write_flights(tmp_path / "b", n_flights=2, axis="lon", seed=8)
    for p, q in zip(paths[:2], again):
        assert p.read_bytes() == q.read_bytes()
        assert p.with_suffix(".json").read_bytes() == q.with_suffix(".json").read_bytes()
    # flight i is drawn from default_rng(seed + i): flight 0 of seed 8 has the amplitude,
    # start and simulation seed of flight 1 of seed 7 (the input type cycles by i)
    t0 = json.loads(other[0].with_suffix(".json").read_text())["truth"]
    t1 = json.loads(paths[1].with_suffix(".json").read_text())["truth"]
    assert t0["seed"] == t1["seed"]
    assert t0["input"]["amplitude"] == t1["input"]["amplitude"]
    assert t0["input"]["type"] != t1["input"]["type"]
    assert other[1].read_bytes() != paths[1].read_bytes()


def test_lat_effect_and_options(tmp_path):
    paths = write_flights(
        tmp_path,
        n_flights=2,
        axis="lat",
        seed=0,
        effect="lon-lat-coupling",
        strength=0.5,
        noise=0.0,
        duration=2.0,
    )
    assert [p.name for p in paths] == ["lat_0.csv", "lat_1.csv"]
    side = json.loads(paths[0].with_suffix(".json").read_text())
    assert side["truth"]["effect"] == "lon-lat-coupling"
    assert side["truth"]["strength"] == 0.5
    assert side["truth"]["input"]["surface"] == "dr"
    header, cols = read_csv(paths[0])
    assert header == CONTRACT_COLUMNS
    assert cols["t"][-1] == pytest.approx(2.0)


def test_noise_free_round_trip_is_exact(tmp_path):
    paths = write_flights(tmp_path, n_flights=1, seed=3, flapping=False, ripple=False, noise=0.0)
    side = json.loads(paths[0].with_suffix(".json").read_text())
    kw = {k: side["truth"]["input"][k] for k in ("start", "unit", "amplitude")}
    fl = simulate_flight(
        axis="lon",
        seed=side["truth"]["seed"],
        input=side["truth"]["input"]["type"],
        flapping=False,
        ripple=False,
        noise=0.0,
        **kw,
    )
    _, cols = read_csv(paths[0])
    for c in COLUMNS:
        np.testing.assert_array_equal(cols[c], fl[c])


def test_loader_reads_written_flights(lon_dir):
    data = pytest.importorskip("fwid.data")
    if not hasattr(data, "load_flight"):
        pytest.skip("fwid.data.load_flight not available")
    _, paths = lon_dir
    fl = data.load_flight(paths[0])
    side = json.loads(paths[0].with_suffix(".json").read_text())
    assert float(fl.trim["theta0"]) == side["trim"]["theta0"]
    assert fl.vehicle is not None and float(fl.vehicle.mass) == DELFLY.mass
    assert fl.first_input == side["first_input"]


def test_truth_columns_and_out_of_catalogue_turbulence(tmp_path):
    import numpy as np

    from fwid.synth import OUT_OF_CATALOGUE, simulate_flight, write_flights

    assert "turbulence" in OUT_OF_CATALOGUE
    p = write_flights(tmp_path, 1, seed=2, effect="turbulence", truth_columns=True)[0]
    header = p.read_text().splitlines()[0].split(",")
    assert {"X_true", "M_true", "N_true"} <= set(header)
    calm = simulate_flight(seed=5, effect="turbulence", strength=0.0)
    none = simulate_flight(seed=5)
    gusty = simulate_flight(seed=5, effect="turbulence", strength=1.0)
    np.testing.assert_array_equal(calm["q"], none["q"])  # strength 0 is exactly none
    dq = gusty["meta"]["clean"]["q"] - none["meta"]["clean"]["q"]
    assert np.std(dq) > 0.02  # gusts move the vehicle by far more than the noise (rad/s)
