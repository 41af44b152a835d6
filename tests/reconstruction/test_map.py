"""Recording maps: a lab's own columns, units and axes read through a TOML map; the pose's
convention checked against the onboard accelerometer; tracking-only takes."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import fwid
from fwid import FlightDataError, InputError
from fwid.cli import main
from fwid.reconstruction import read_map, read_raw

from .helpers import VEHICLE, Motion, noisy, write_vehicle

T = np.arange(0, 4, 0.01)  # 100 Hz, as an autopilot logs
Z_UP = np.diag([1.0, -1.0, -1.0])  # z-up <-> NED, world and body axes alike
MAP = """
[time]
column = "tick"
unit = "ms"

[tracking]
position = ["X", "Y", "Z"]
position_unit = "mm"
frame = "z-up"
attitude = ["roll", "pitch", "yaw"]
attitude_unit = "deg"
euler = "ZYX"

[onboard]
file = "{name}.csv"
acc = ["ax", "ay", "az"]
acc_unit = "g"
axes = "flu"

[inputs]
de = { column = "servo", offset = 32767, scale = 1e-5 }
f = { column = ["left", "right"], offset = 100, scale = 0.001 }
"""


def lab_columns(motion, t, *, pitch_sign=1.0, seed=0, jitter=True):
    """A lab's logged columns: ms ticks (jittered by a tick), the pose in a z-up frame in mm
    with ZYX Euler angles in degrees (pitch logged with `pitch_sign`), the accelerometer in g
    in forward-left-up axes, a servo and two motor commands."""
    rng = np.random.default_rng(seed)
    pos, R = noisy(motion, t, rng)
    pos_z, R_z = pos @ Z_UP.T, Z_UP @ R @ Z_UP.T
    ypr = Rotation.from_matrix(R_z).as_euler("ZYX", degrees=True)
    a = motion.acc(t)
    f_body = np.einsum("nji,nj->ni", motion.R(t), a - [0, 0, VEHICLE["g"]])
    acc = f_body * [1, -1, -1] / 9.80665 + 0.01 * rng.standard_normal((len(t), 3))
    tick = np.round(t * 1e3).astype(int)
    if jitter:
        tick[len(t) // 2] += 1
    servo = 32767 + 1e4 * np.sin(2 * np.pi * 0.5 * t)
    motor = 100 + 12000.0 + 0 * t
    return {"tick": tick, "X": pos_z[:, 0] * 1e3, "Y": pos_z[:, 1] * 1e3, "Z": pos_z[:, 2] * 1e3,
            "roll": ypr[:, 2], "pitch": pitch_sign * ypr[:, 1], "yaw": ypr[:, 0],
            "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2], "servo": servo, "left": motor,
            "right": motor}


def write_columns(path, cols, cut_last=False):
    """`cols` as a CSV file with one header row (numbers to 6 decimals)."""
    lines = [", ".join(cols)]
    for row in zip(*cols.values()):
        lines.append(", ".join(f"{v:.6f}" if not isinstance(v, (int, np.integer)) else str(v)
                               for v in row))
    if cut_last:
        lines.append(lines[-1][:20])
    path.write_text("\n".join(lines) + "\n")
    write_vehicle(path.parent)
    return path


def write_lab_take(path, motion, t, *, pitch_sign=1.0, seed=0, jitter=True, cut_last=True):
    """A lab's log (`lab_columns`) as a CSV file, its last line cut short (`cut_last`)."""
    return write_columns(path, lab_columns(motion, t, pitch_sign=pitch_sign, seed=seed,
                                           jitter=jitter), cut_last)


@pytest.fixture(scope="module")
def motion():
    return Motion(seed=4)


def _map(tmp_path, text=MAP):
    p = tmp_path / "lab.toml"
    p.write_text(text)
    return p


def test_map_errors_name_the_key(tmp_path):
    with pytest.raises(InputError, match=r"\[tracking\] frame.*'up'"):
        read_map(_map(tmp_path, MAP.replace('frame = "z-up"', 'frame = "up"')))
    with pytest.raises(InputError, match=r"\[onboard\] acc_units.*unknown key"):
        read_map(_map(tmp_path, MAP.replace("acc_unit", "acc_units")))
    with pytest.raises(InputError, match=r"\[tracking\] position.*3 column"):
        read_map(_map(tmp_path, MAP.replace('["X", "Y", "Z"]', '["X", "Y"]')))
    with pytest.raises(InputError, match="not valid TOML"):
        read_map(_map(tmp_path, MAP + "\n[inputs\n"))
    m = read_map(_map(tmp_path))
    assert m.time_scale == 1e-3 and m.position_scale == 1e-3 and m.euler == "ZYX"
    assert m.inputs["f"].columns == ("left", "right") and m.log_is_take


def test_missing_column_names_map_and_file(tmp_path, motion):
    take = write_lab_take(tmp_path / "a.csv", motion, T)
    with pytest.raises(FlightDataError, match=r"a\.csv: no column 'servo2'.*lab\.toml"):
        read_raw(take, recording_map=_map(tmp_path, MAP.replace('"servo"', '"servo2"')))


def test_reversed_pitch_found_by_the_accelerometer(tmp_path, motion):
    """The logger writes pitch with the opposite sign: the accelerometer contradicts the
    map's reading and agrees with pitch reversed, which is used and named; the states then
    match the truth, the jittered tick is resampled and the cut-short line dropped."""
    take = write_lab_take(tmp_path / "a.csv", motion, T, pitch_sign=-1.0)
    res = fwid.reconstruct(take, recording_map=_map(tmp_path))
    assert not res.failures, res.failures
    fl = res.flights[0]
    warn = " | ".join(fl.entry["warnings"])
    assert "pitch reversed" in warn and "cut short" in warn and "jitter" in warn
    assert fl.entry["imu"]["frame"] == "z-up frame, pitch reversed, sensors FLU"
    for ax in "xyz":
        assert fl.entry["imu"]["acc"][ax]["corr"] > 0.95, fl.entry["imu"]
    c = fl.columns
    t = c["t"]
    truth = motion.euler(t)
    inner = slice(40, -40)
    np.testing.assert_allclose(c["theta"][inner], truth[inner, 1], atol=0.02)
    V = np.einsum("nji,nj->ni", motion.R(t), motion.vel(t))
    np.testing.assert_allclose(c["u"][inner], V[inner, 0], atol=0.05)
    np.testing.assert_allclose(c["de"], 0.1 * np.sin(2 * np.pi * 0.5 * t), atol=2e-3)
    np.testing.assert_allclose(c["f"], 12.0, atol=1e-9)
    with pytest.raises(FlightDataError, match="pitch reversed.*--strict-frame"):
        read_raw(take, recording_map=_map(tmp_path), strict_frame=True)


def test_map_that_is_right_is_kept(tmp_path, motion):
    take = write_lab_take(tmp_path / "b.csv", motion, T, jitter=False, cut_last=False)
    tk = read_raw(take, recording_map=_map(tmp_path), strict_frame=True)
    assert tk.warnings == [] and tk.convention.angle_signs == (1.0, 1.0, 1.0)


def test_cli_with_map_and_tracking_only(tmp_path, motion, capsys):
    """`--map` on the command line; the same take without inputs or sensors is tracking
    only: f from the pose's ripple, no de column."""
    take = write_lab_take(tmp_path / "a.csv", motion, T)
    assert main(["reconstruct", str(take), "--map", str(_map(tmp_path)), "--out",
                 str(tmp_path / "out"), "--no-figures", "--quiet"]) == 0
    bare = MAP.split("[onboard]")[0]
    assert main(["reconstruct", str(take), "--map", str(_map(tmp_path, bare)), "--out",
                 str(tmp_path / "bare"), "--no-figures", "--quiet"]) == 0
    header = (tmp_path / "bare" / "a.csv").read_text().splitlines()[0].split(",")
    assert "de" not in header and "f" in header
    import json

    entry = json.loads((tmp_path / "bare" / "reconstruction.json").read_text())["flights"][0]
    assert any("ripple" in w for w in entry["warnings"]), entry["warnings"]
    f = np.loadtxt(tmp_path / "bare" / "a.csv", delimiter=",", skiprows=1,
                   usecols=header.index("f"))
    assert abs(np.median(f) - 12.0) < 0.1
    assert main(["reconstruct", str(take), "--map", str(tmp_path / "none.toml"), "--out",
                 str(tmp_path / "x")]) == 2
    assert "none.toml: no such file" in capsys.readouterr().err


@pytest.mark.parametrize("change, words", [
    (('acc_unit = "g"', 'acc_unit = "m/s2"'), ['acc_unit = "g"', "about g"]),
    (('unit = "ms"', 'unit = "s"'), ['set [time] unit = "ms"']),
    (('attitude_unit = "deg"', 'attitude_unit = "rad"'), ['attitude_unit = "deg"', "beyond pi"]),
    (('"servo"', '"serv"'), ["'serv' (did you mean 'servo'?)"]),
])
def test_a_slip_in_the_map_is_named_with_its_fix(tmp_path, motion, change, words):
    """A unit or column the data contradict is refused in one line naming the map's key and
    the value that fits (an accelerometer in g read as m/s^2 would otherwise flip the frame
    the sensors check)."""
    take = write_lab_take(tmp_path / "a.csv", motion, T)
    with pytest.raises(FlightDataError) as e:
        read_raw(take, recording_map=_map(tmp_path, MAP.replace(*change)))
    msg = str(e.value)
    assert "\n" not in msg and all(w in msg for w in words), msg
