"""Raw recordings of the 6-DOF flights (docs/reference/formats.md): the files parse back as
RAWFORMS lays them out, the y-up frame maps back to north-east-down, and the pose noise,
dropout share and autopilot clock are as asked. The parsing here is written independently
of the writer (scipy's Rotation for the attitude)."""

import csv
import json

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from fwid.synth import COLUMNS, RAW_COLUMNS, write_raw_flights

C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # NED <- y-up (RAWFORMS b)
OFFSET = -137.123456789


def _truth(folder, name="lon_0"):
    with open(folder / "truth" / f"{name}.csv") as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(folder / "truth" / f"{name}.csv", delimiter=",", skiprows=1)
    meta = json.loads((folder / "truth" / f"{name}.json").read_text())
    return {c: data[:, i] for i, c in enumerate(header)}, header, meta


def _read_motive(path, body):
    """Lines 1-7 of the export, then the body's quaternion (X Y Z W) and position columns."""
    with open(path) as fh:
        rows = list(csv.reader(fh))
    head = dict(zip(rows[0][::2], rows[0][1::2]))
    assert rows[1] == []
    types, names, ids, groups, axes = rows[2], rows[3], rows[4], rows[5], rows[6]
    assert types[1] == "Type" and names[1] == "Name" and ids[1] == "ID"
    assert axes[:2] == ["Frame", "Time (Seconds)"]
    cols = {}
    for j in range(2, len(axes)):
        if types[j] == "Rigid Body" and names[j] == body and groups[j] in ("Rotation", "Position"):
            cols[(groups[j], axes[j])] = j
    data = np.array([[float(v) if v != "" else np.nan for v in r] for r in rows[7:]])
    quat = np.column_stack([data[:, cols[("Rotation", a)]] for a in "XYZW"])  # scalar last
    pos = np.column_stack([data[:, cols[("Position", a)]] for a in "XYZ"])
    return head, names, data[:, 0], data[:, 1], quat, pos


@pytest.fixture(scope="module")
def clean_motive(tmp_path_factory):
    out = tmp_path_factory.mktemp("motive")
    write_raw_flights(out, raw="motive", n_flights=1, seed=4, duration=7.0, position_noise=0.0,
                      attitude_noise=0.0, dropouts=0.0, clock_offset=OFFSET, onboard_rate=100.0)
    return out


@pytest.fixture(scope="module")
def noisy_fwid(tmp_path_factory):
    out = tmp_path_factory.mktemp("fwid")
    write_raw_flights(out, raw="fwid", n_flights=1, seed=5, duration=7.0, dropouts=0.01)
    return out


def test_motive_layout_and_y_up_round_trip(clean_motive):
    truth, header, meta = _truth(clean_motive)
    assert header[: len(COLUMNS)] == list(COLUMNS)
    head, names, frame, t, quat_m, pos_mm = _read_motive(clean_motive / "lon_0.csv", "DelFly")
    assert head["Format Version"] == "1.23" and head["Rotation Type"] == "Quaternion"
    assert head["Length Units"] == "Millimeters" and float(head["Capture Frame Rate"]) == 200.0
    assert int(head["Total Exported Frames"]) == len(t) == len(truth["t"])
    assert "Wand" in names  # a second rigid body, so that --body matters
    np.testing.assert_array_equal(frame, np.arange(len(t)))
    np.testing.assert_allclose(t, truth["t"], atol=1e-9)
    # y-up mm -> NED m, for the world and the body axes alike
    pos = (pos_mm / 1000.0) @ C.T
    np.testing.assert_allclose(pos, np.column_stack([truth[c] for c in "xyz"]), atol=1e-8)
    R_ned = C @ Rotation.from_quat(quat_m).as_matrix() @ C.T
    euler = Rotation.from_matrix(R_ned).as_euler("ZYX")  # psi, theta, phi
    np.testing.assert_allclose(euler[:, 1], truth["theta"], atol=1e-7)
    np.testing.assert_allclose(np.angle(np.exp(1j * (euler[:, 2] - truth["phi"]))), 0, atol=1e-7)
    np.testing.assert_allclose(np.angle(np.exp(1j * (euler[:, 0] - truth["psi"]))), 0, atol=1e-7)
    # the vehicle is nose-up (theta ~ 73 deg): its nose points mostly up, +Y in Motive
    nose = Rotation.from_quat(quat_m).apply([1.0, 0.0, 0.0])
    assert np.all(nose[:, 1] > 0.8)


def test_onboard_log_clock_rate_and_gyro(clean_motive):
    truth, _, meta = _truth(clean_motive)
    raw = meta["truth"]["raw"]
    assert raw["clock_offset_s"] == OFFSET
    ob = np.genfromtxt(clean_motive / "lon_0.onboard.csv", delimiter=",", names=True)
    assert list(ob.dtype.names) == ["t", "de", "dr", "f", "p", "q", "r"]
    np.testing.assert_allclose(np.diff(ob["t"]), 0.01, rtol=1e-6)
    # the log starts shortly after the take (tracking time) and overlaps it
    t_track = ob["t"] + OFFSET
    assert 0.05 <= t_track[0] <= 0.25 and t_track[-1] > truth["t"][-1]
    inside = t_track <= truth["t"][-1]
    bias = np.array(raw["gyro_bias"])
    res = {}
    for shift in (0.0, 0.002):  # the true clock, and one 2 ms off
        res[shift] = [np.std(ob[c][inside] - bias[i]
                             - CubicSpline(truth["t"], truth[c])(t_track[inside] + shift))
                      for i, c in enumerate("pqr")]
    noise = raw["gyro_noise"]
    for i in range(3):
        assert res[0.0][i] == pytest.approx(noise, rel=0.2), res
    assert res[0.002][1] > 3 * noise  # the pitch rate's flapping shows a 2 ms error
    np.testing.assert_allclose(ob["f"][inside], np.interp(t_track[inside], truth["t"], truth["f"]),
                               atol=0.1)


def test_fwid_raw_noise_dropouts_and_sign_flips(noisy_fwid):
    truth, _, meta = _truth(noisy_fwid)
    with open(noisy_fwid / "lon_0.csv") as fh:
        assert fh.readline().strip() == ",".join(RAW_COLUMNS)
    d = np.genfromtxt(noisy_fwid / "lon_0.csv", delimiter=",", names=True)
    n = len(d)
    np.testing.assert_allclose(d["t"], truth["t"], atol=1e-12)
    lost = np.isnan(d["x"])
    for c in ("y", "z", "qw", "qx", "qy", "qz"):
        np.testing.assert_array_equal(np.isnan(d[c]), lost)
    assert not np.isnan(d["de"]).any() and not np.isnan(d["f"]).any()
    assert lost.sum() == round(0.01 * n)
    edges = np.flatnonzero(np.diff(lost.astype(int)))
    lengths = edges[1::2] - edges[::2]
    assert lengths.min() >= 1 and lengths.max() <= 8 and len(lengths) >= 3
    assert meta["truth"]["raw"]["dropout_share"] == pytest.approx(lost.mean())
    ok = ~lost
    err = np.column_stack([d[c][ok] - truth[c][ok] for c in "xyz"])
    np.testing.assert_allclose(err.std(axis=0), 4e-4, rtol=0.1)
    q = np.column_stack([d[c][ok] for c in ("qw", "qx", "qy", "qz")])
    qt = np.column_stack([truth[c][ok] for c in ("qw", "qx", "qy", "qz")])
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-8)
    sign = np.sign(np.sum(q * qt, axis=1))
    assert 0.01 < np.mean(sign < 0) < 0.2  # q and -q both occur
    # attitude noise: the body-axis rotation from truth to measurement, per axis
    rel = (Rotation.from_quat(qt[:, [1, 2, 3, 0]]).inv()
           * Rotation.from_quat(q[:, [1, 2, 3, 0]])).as_rotvec()
    np.testing.assert_allclose(np.rad2deg(rel.std(axis=0)), 0.15, rtol=0.1)
    # the controls and the flapping frequency, measured on the take's time base
    assert np.std(d["de"] - truth["de"]) == pytest.approx(0.002, rel=0.15)


def test_truth_loads_obey_the_rigid_body_equations(clean_motive):
    """`X Y Z = m (V' + w x V) - m R^T g` and `L M N = I w' + w x I w` on the truth's own
    states (8th-order differences, scipy's rotation): the loads and the motion belong together,
    with the product of inertia."""
    from fwid.synth import DELFLY, derivative

    truth, _, _ = _truth(clean_motive)
    dt = truth["t"][1] - truth["t"][0]
    V = np.column_stack([truth[c] for c in "uvw"])
    om = np.column_stack([truth[c] for c in "pqr"])
    R = Rotation.from_quat(np.column_stack([truth[c] for c in ("qx", "qy", "qz", "qw")])).as_matrix()
    m, g = DELFLY.mass, DELFLY.g
    I = np.array([[DELFLY.Ix, 0, -DELFLY.Ixz], [0, DELFLY.Iy, 0], [-DELFLY.Ixz, 0, DELFLY.Iz]])
    F = m * (derivative(V, dt) + np.cross(om, V)) - m * g * R[:, 2, :]
    Mo = derivative(om, dt) @ I.T + np.cross(om, om @ I.T)
    inner = slice(10, -10)
    for i, c in enumerate("XYZLMN"):
        got = (F if i < 3 else Mo)[inner, i % 3]
        ref = truth[c][inner]
        assert np.sqrt(np.mean((got - ref) ** 2)) < 0.01 * np.sqrt(np.mean(ref**2)), c


def test_an_injected_effect_reaches_the_6dof_flight():
    """`--effect` applies to raw flights too: an actuator lag changes the 6-DOF pitch
    response and is recorded in the truth."""
    from fwid.synth import simulate_raw

    kw = dict(seed=2, duration=7.0, position_noise=0.0, attitude_noise=0.0, dropouts=0.0,
              onboard=False, input="doublet", start=1.0)
    plain = simulate_raw(**kw)
    lagged = simulate_raw(effect="actuator-dynamics", strength=3.0, **kw)
    q0, q1 = plain["truth"]["q"], lagged["truth"]["q"]
    assert np.sqrt(np.mean((q1 - q0) ** 2)) > 0.02 * np.ptp(q0)
    assert lagged["meta"]["truth"]["effect"] == "actuator-dynamics"
    assert plain["meta"]["truth"]["effect"] == "none"
    np.testing.assert_allclose(q1[:150], q0[:150], atol=1e-9)  # identical before the input
