"""Recording maps over array files (MATLAB v5 and v7.3, NumPy, HDF5), other attitude forms,
and a tracking stream slower than its log."""

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import fwid
from fwid import FlightDataError
from fwid.cli import main
from fwid.reconstruction import read_raw
from fwid.synth._labmat import LAB_MAP

from .helpers import Motion, write_vehicle
from .test_map import MAP, T, lab_columns, write_columns

#: The lab's MATLAB map (the simulator's, `fwid.synth._labmat.LAB_MAP`) with the onboard
#: accelerometer in a struct.
MAT_MAP = LAB_MAP.split("[onboard]")[0] + """[onboard]
file = "{name}.mat"
acc = ["imu.acc[0,0]", "imu.acc[1,0]", "imu.acc[2,0]"]
acc_unit = "g"
axes = "flu"

[inputs]
de = { column = "record_PWM[0]", offset = 32767, scale = 1e-5 }
f = { column = ["record_PWM[1]", "record_PWM[2]"], offset = 100, scale = 0.001 }
"""


@pytest.fixture(scope="module")
def motion():
    return Motion(seed=4)


def matlab_log(c):
    """The lab's columns laid out as a MATLAB logger writes them: a 1 x N time stamp, an
    N x 6 pose (mm, deg), an N x 3 x 1 accelerometer in a struct, N x 4 PWM outputs."""
    n = len(c["tick"])
    return {"record_time_stamp": c["tick"][None, :].astype(float),
            "record_Sensor_data": np.column_stack([c[k] for k in ("X", "Y", "Z", "roll", "pitch",
                                                                  "yaw")]),
            "imu": {"acc": np.column_stack([c["ax"], c["ay"], c["az"]])[:, :, None]},
            "record_PWM": np.column_stack([c["servo"], c["left"], c["right"], np.zeros(n)])}


def write_h5(path, log, transposed, userblock=0):
    """`log` in an HDF5 file (structs as groups); `transposed`: as MATLAB v7.3 stores it."""
    h5py = pytest.importorskip("h5py")
    path.parent.mkdir(exist_ok=True)
    with h5py.File(path, "w", userblock_size=userblock) as fh:
        def put(group, d):
            for k, v in d.items():
                if isinstance(v, dict):
                    put(group.create_group(k), v)
                else:
                    group[k] = v.T if transposed else v
        put(fh, log)
    write_vehicle(path.parent)
    return path


def _maps(tmp_path, **texts):
    out = {}
    for name, text in texts.items():
        out[name] = tmp_path / f"{name}.toml"
        out[name].write_text(text)
    return out


def test_matlab_log_equals_the_csv(tmp_path, motion):
    """The same log as CSV and as a MATLAB v5 file (savemat) reconstructs to the same states;
    a v7.3 file (HDF5, column-major, behind a 512-byte header) reads the same pose."""
    from scipy.io import savemat

    c = lab_columns(motion, T)
    csv = write_columns(tmp_path / "a.csv", c)
    mat = tmp_path / "m" / "a.mat"
    mat.parent.mkdir()
    savemat(mat, matlab_log(c))
    write_vehicle(mat.parent)
    maps = _maps(tmp_path, csv=MAP, mat=MAT_MAP)
    ref = fwid.reconstruct(csv, recording_map=maps["csv"])
    got = fwid.reconstruct(mat, recording_map=maps["mat"])
    assert not ref.failures and not got.failures, (ref.failures, got.failures)
    a, b = ref.flights[0].columns, got.flights[0].columns
    assert set(a) == set(b)
    for k in a:  # the CSV holds 6 decimals of mm and degrees
        np.testing.assert_allclose(b[k], a[k], atol=1e-5, rtol=1e-5, err_msg=k)
    v73 = write_h5(tmp_path / "h" / "a.mat", matlab_log(c), transposed=True, userblock=512)
    t5, t73 = (read_raw(p, recording_map=maps["mat"]) for p in (mat, v73))
    np.testing.assert_array_equal(t73.pos, t5.pos)
    np.testing.assert_array_equal(t73.quat, t5.quat)
    np.testing.assert_array_equal(t73.controls["de"], t5.controls["de"])


def test_npz_and_hdf5_with_dotted_paths(tmp_path, motion):
    """An `.npz` of plain columns and an `.h5` file with the pose in groups read as the CSV."""
    c = lab_columns(motion, T, jitter=False)
    csv = write_columns(tmp_path / "a.csv", c)
    np.savez(tmp_path / "b.npz", **{k: np.asarray(v, float) for k, v in c.items()})
    h5 = write_h5(tmp_path / "c.h5", {"take": {"time": c["tick"].astype(float), "RigidBodies": {
        "Positions": np.column_stack([c["X"], c["Y"], c["Z"]]),
        "Angles": np.column_stack([c["roll"], c["pitch"], c["yaw"]])}}}, transposed=False)
    bare = MAP.split("[onboard]")[0]
    dotted = (bare.replace('"tick"', '"take.time"')
              .replace('["X", "Y", "Z"]', '["take.RigidBodies.Positions[0]", '
                       '"take.RigidBodies.Positions[1]", "take.RigidBodies.Positions[2]"]')
              .replace('["roll", "pitch", "yaw"]', '["take.RigidBodies.Angles[0]", '
                       '"take.RigidBodies.Angles[1]", "take.RigidBodies.Angles[2]"]'))
    maps = _maps(tmp_path, csv=bare, npz=bare.replace("{name}.csv", "{name}.npz"), h5=dotted)
    ref = read_raw(csv, recording_map=maps["csv"])
    for path, m in ((tmp_path / "b.npz", maps["npz"]), (h5, maps["h5"])):
        got = read_raw(path, recording_map=m)
        assert got.name == path.stem
        np.testing.assert_allclose(got.pos, ref.pos, atol=1e-8)
        np.testing.assert_allclose(got.quat, ref.quat, atol=1e-8)


def test_array_file_mistakes_are_one_line(tmp_path, motion, capsys):
    """A missing variable names the key, the file and what it holds (exit 2 on the command
    line); an index out of range and a time base far off the data are refused; one or two
    samples off are trimmed with a warning."""
    from scipy.io import savemat

    c = lab_columns(motion, T, jitter=False)
    log = matlab_log(c)
    mat = tmp_path / "a.mat"
    savemat(mat, log)
    write_vehicle(tmp_path)
    maps = _maps(tmp_path, good=MAT_MAP,
                 missing=MAT_MAP.replace("record_Sensor_data[0]", "record_Sensor[0]"),
                 index=MAT_MAP.replace("record_PWM[0]", "record_PWM[7]"))
    with pytest.raises(FlightDataError) as e:
        read_raw(mat, recording_map=maps["missing"])
    msg = str(e.value)
    assert ("[tracking] position: no variable 'record_Sensor' in a.mat; it holds "
            in msg and "record_Sensor_data" in msg and "imu.acc" in msg and "\n" not in msg), msg
    with pytest.raises(FlightDataError, match=r"\[inputs\] de: 'record_PWM\[7\]'.*out of range"):
        read_raw(mat, recording_map=maps["index"])
    assert main(["reconstruct", str(mat), "--map", str(maps["missing"]), "--out",
                 str(tmp_path / "x"), "--no-figures", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "no variable 'record_Sensor'" in err and len(err.splitlines()) == 1, err
    # the time base two samples longer than the data: trimmed; seven: refused
    for extra, ok in ((2, True), (7, False)):
        t = np.concatenate([log["record_time_stamp"][0], log["record_time_stamp"][0, -1]
                            + 10.0 * np.arange(1, extra + 1)])
        savemat(mat, {**log, "record_time_stamp": t[None, :]})
        if ok:
            tk = read_raw(mat, recording_map=maps["good"])
            assert len(tk.t) == len(T)
            assert any("trimmed to the common 400" in w for w in tk.warnings), tk.warnings
        else:
            with pytest.raises(FlightDataError, match="400 samples against the time base's 407"):
                read_raw(mat, recording_map=maps["good"])


def test_matrix_attitude_and_qualisys_order(tmp_path, motion):
    """Nine rotation-matrix columns (row-major, body to lab), and angles in the XYZ order,
    read the same pose as the ZYX angles."""
    c = lab_columns(motion, T, jitter=False)
    R = Rotation.from_euler("ZYX", np.column_stack([c["yaw"], c["pitch"], c["roll"]]),
                            degrees=True)
    M = R.as_matrix().reshape(-1, 9)
    xyz = R.as_euler("XYZ", degrees=True)
    more = {**c, **{f"r{i}": M[:, i] for i in range(9)},
            "rx": xyz[:, 0], "ry": xyz[:, 1], "rz": xyz[:, 2]}
    take = write_columns(tmp_path / "a.csv", more)
    bare = MAP.split("[onboard]")[0]
    nine = ", ".join(f'"r{i}"' for i in range(9))
    maps = _maps(tmp_path, zyx=bare,
                 matrix=bare.replace('["roll", "pitch", "yaw"]', f"[{nine}]")
                 .replace('euler = "ZYX"', 'attitude_form = "matrix"'),
                 xyz=bare.replace('["roll", "pitch", "yaw"]', '["rx", "ry", "rz"]')
                 .replace('"ZYX"', '"XYZ"'))
    ref = read_raw(take, recording_map=maps["zyx"])
    for name in ("matrix", "xyz"):
        got = read_raw(take, recording_map=maps[name])
        np.testing.assert_allclose(got.quat, ref.quat, atol=2e-6, err_msg=name)


def test_tracking_slower_than_its_log(tmp_path, motion):
    """Every other row repeats the previous pose (tracking at half the log's rate) and one
    row is logged twice: the take is read, not refused; the pose comes from the fresh
    samples, the controls keep the log's rate, both rates are named."""
    t = np.arange(0, 4, 0.01)
    c = lab_columns(motion, t, jitter=False)
    for k in ("X", "Y", "Z", "roll", "pitch", "yaw"):
        c[k] = c[k].copy()
        c[k][1::2] = c[k][0:-1:2]
    dup = 101
    c = {k: np.insert(v, dup, v[dup]) for k, v in c.items()}
    take = write_columns(tmp_path / "a.csv", c)
    m = _maps(tmp_path, m=MAP)["m"]
    assert main(["reconstruct", str(take), "--map", str(m), "--out", str(tmp_path / "out"),
                 "--no-figures", "--quiet"]) == 0
    entry = json.loads((tmp_path / "out" / "reconstruction.json").read_text())["flights"][0]
    assert abs(entry["tracking_rate_hz"] - 50.0) < 1.0 and abs(entry["rate_hz"] - 100.0) < 0.5
    warn = " | ".join(entry["warnings"])
    assert "slower than the log's 100 Hz" in warn and "merged" in warn, warn
    assert "dropped as dropouts" not in warn and entry["dropouts"] == [], warn
    assert "no convention" not in warn and entry["imu"]["acc"]["z"]["corr"] > 0.95, entry["imu"]
    header = (tmp_path / "out" / "a.csv").read_text().splitlines()[0].split(",")
    out = np.loadtxt(tmp_path / "out" / "a.csv", delimiter=",", skiprows=1)
    col = {h: out[:, i] for i, h in enumerate(header)}
    inner = slice(40, -40)
    truth = motion.euler(col["t"])
    np.testing.assert_allclose(col["theta"][inner], truth[inner, 1], atol=0.03)
    np.testing.assert_allclose(col["de"], 0.1 * np.sin(2 * np.pi * 0.5 * col["t"]), atol=2e-3)


def test_pose_in_a_file_of_its_own(tmp_path, motion, capsys):
    """`[tracking] file`: the pose in `NAME_mocap.npz` beside the autopilot's log `NAME.csv`
    (on its own clock) reconstructs as the one file holding both; in a folder the pose's
    file is no take of its own; a missing pose file is one line."""
    c = lab_columns(motion, T, jitter=False)
    pose = ("tick", "X", "Y", "Z", "roll", "pitch", "yaw")
    log = {"t": c["tick"] / 1e3, "servo": c["servo"], "left": c["left"], "right": c["right"]}
    text = MAP.replace('file = "{name}.csv"\nacc = ["ax", "ay", "az"]\nacc_unit = "g"\n'
                       'axes = "flu"', 'time = "t"')
    same = tmp_path / "same"  # the pose in the take, the log in NAME.onboard.csv
    same.mkdir()
    write_vehicle(same)
    write_columns(same / "a.csv", {k: c[k] for k in pose})
    write_columns(same / "a.onboard.csv", log)
    folder = tmp_path / "lab"  # the log as the recording, the pose in a file of its own
    folder.mkdir()
    write_vehicle(folder)
    np.savez(folder / "a_mocap.npz", **{k: np.asarray(c[k], float) for k in pose})
    write_columns(folder / "a.csv", log)
    maps = _maps(tmp_path, same=text, lab=text.replace(
        "[tracking]\n", '[tracking]\nfile = "{name}_mocap.npz"\n').replace(
        "[onboard]\n", '[onboard]\nfile = "{name}.csv"\n'))
    m = maps["lab"]
    ref = fwid.reconstruct(same, recording_map=maps["same"])
    assert fwid.reconstruction.raw_files(folder, m) == [folder / "a.csv"]
    got = fwid.reconstruct(folder, recording_map=m)
    assert not ref.failures and not got.failures, (ref.failures, got.failures)
    (a,), (b,) = ref.flights, got.flights
    assert b.name == "a" and "a_mocap.npz" in b.entry["source"]
    for k in ("u", "w", "q", "theta", "de"):
        np.testing.assert_allclose(b.columns[k], a.columns[k], atol=1e-5, err_msg=k)
    (folder / "a_mocap.npz").unlink()
    assert main(["reconstruct", str(folder / "a.csv"), "--map", str(m),
                 "--out", str(tmp_path / "out")]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if "error" in ln]
    assert len(err) == 1 and "a_mocap.npz" in err[0] and "[tracking] file" in err[0], err


def test_two_takes_of_one_name_are_refused(tmp_path, motion, capsys):
    """`a.csv` and `a.npz` in one folder would write one flight `a.csv`: refused on the command
    line before any work, naming both; nothing is written."""
    c = lab_columns(motion, T, jitter=False)
    write_columns(tmp_path / "a.csv", c)
    np.savez(tmp_path / "a.npz", **{k: np.asarray(v, float) for k, v in c.items()})
    write_vehicle(tmp_path)
    m = _maps(tmp_path, m=MAP)["m"]
    out = tmp_path / "out"
    assert main(["reconstruct", str(tmp_path), "--map", str(m), "--out", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if "error" in ln]
    assert len(err) == 1 and "two takes named 'a'" in err[0] and "a.npz" in err[0], err
    assert not out.exists()
