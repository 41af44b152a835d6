"""Motive exports as Motive writes them: a rounded time column, missing frames, no
`Length Units`, Euler angles in each rotation order, the old layout; and the real five-body
export in `../shared/realdata/`."""

import numpy as np
import pytest

from fwid import FlightDataError
from fwid.cli import main
from fwid.reconstruction import read_raw

from .helpers import REAL, Motion, noisy, write_motive

RATE = 120.0
T = np.arange(0, 4, 1 / RATE)


@pytest.fixture(scope="module")
def motion():
    return Motion(seed=2)


@pytest.fixture(scope="module")
def pose(motion):
    return noisy(motion, T, np.random.default_rng(0))


def _read(tmp_path, motion, pose, name="take", **kw):
    (tmp_path / name).mkdir(exist_ok=True)
    path = write_motive(tmp_path / name / "take.csv", motion, T, pos=pose[0], R=pose[1], **kw)
    return path, read_raw(path, body="DelFly")


def _same_pose(a, b, pos_tol=1e-9):
    assert np.array_equal(a.tracked, b.tracked)
    ok = a.tracked
    assert np.max(np.abs(a.pos[ok] - b.pos[ok])) < pos_tol
    assert np.max(1 - np.abs(np.sum(a.quat[ok] * b.quat[ok], 1))) < 1e-10


def test_millisecond_time_column_reads_on_frames(tmp_path, motion, pose):
    """Motive's time column truncated to the millisecond (0.008, 0.016, 0.025 ...): the time
    base is Frame / rate, uniform, with nothing to warn about."""
    _, take = _read(tmp_path, motion, pose, time_decimals=3)
    assert np.allclose(np.diff(take.t), 1 / RATE, rtol=0, atol=1e-12)
    assert take.warnings == [] and take.dropouts == [] and take.tracked.all()


def test_missing_frames_are_dropouts(tmp_path, motion, pose):
    _, ref = _read(tmp_path, motion, pose, name="ref")
    _, take = _read(tmp_path, motion, pose, name="gap", missing=[(100, 105), (300, 301)],
                    time_decimals=3)
    assert np.allclose(take.t, ref.t, atol=1e-12)
    assert np.array_equal(np.flatnonzero(~take.tracked), [100, 101, 102, 103, 104, 300])
    assert take.dropouts == [[T[100], T[104]], [T[300], T[300]]]
    assert take.warnings == ["6 frames missing from the export (first frame 100, t = 0.833333 "
                             "s): bridged as dropouts"]
    ok = take.tracked
    assert np.max(np.abs(take.pos[ok] - ref.pos[ok])) < 1e-9


def test_a_long_run_of_missing_frames_is_refused_by_the_cli(tmp_path, motion, pose, capsys):
    """Missing frames split the take; neither side lasts the 5 s an identification needs."""
    path = write_motive(tmp_path / "take.csv", motion, T, pos=pose[0], R=pose[1],
                        missing=[(200, 240)], time_decimals=3)
    rc = main(["reconstruct", str(path), "--out", str(tmp_path / "out"), "--quiet",
               "--body", "DelFly"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "lost for 0.333 s from t = 1.66667 s to 1.99167 s" in err[0], err
    assert "under the 5 s" in err[0] and "--max-dropout" in err[0]


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
def test_euler_export_reads_like_the_quaternion_one(tmp_path, motion, pose, order):
    _, q = _read(tmp_path, motion, pose, name="q")
    _, e = _read(tmp_path, motion, pose, name=order, rotation=order)
    assert e.source.endswith(f"{order} Euler)")
    # 6 decimals of a degree: about 1e-8 rad
    ok = q.tracked
    assert np.array_equal(q.tracked, e.tracked) and np.max(np.abs(q.pos[ok] - e.pos[ok])) < 1e-9
    assert np.max(1 - np.abs(np.sum(q.quat[ok] * e.quat[ok], 1))) < 1e-12


def test_euler_order_matters(tmp_path, motion, pose):
    """Angles written in one order and declared in another read a different attitude: the
    header's order is used."""
    path, _ = _read(tmp_path, motion, pose, name="xyz", rotation="XYZ")
    _, q = _read(tmp_path, motion, pose, name="q")
    text = path.read_text().replace("Rotation Type,XYZ", "Rotation Type,ZYX", 1)
    path.write_text(text)
    wrong = read_raw(path, body="DelFly", max_dropout=1.0)  # wrong attitudes jump: glitches
    ok = wrong.tracked
    assert np.median(1 - np.abs(np.sum(q.quat[ok] * wrong.quat[ok], 1))) > 1e-3


@pytest.mark.parametrize("units, read_as", [("Millimeters", "millimeters"), ("Meters", "meters")])
def test_length_units_absent_are_inferred_and_said(tmp_path, motion, pose, units, read_as):
    _, ref = _read(tmp_path, motion, pose, name="ref", units=units)
    _, take = _read(tmp_path, motion, pose, name="guess", units=units, length_key=False)
    _same_pose(ref, take)
    assert len(take.warnings) == 1 and take.warnings[0].startswith(
        f"the header names no Length Units: positions read as {read_as} (they reach ")


def test_length_units_absent_and_undecidable_are_refused(tmp_path, motion, pose):
    """Positions 50 units from the origin: 50 m is beyond a tracking room, 5 cm no flight."""
    pos = pose[0] * 0.001 + [0.0, 0.0, -50.0]  # y-up Y = 50
    path = write_motive(tmp_path / "take.csv", motion, T, pos=pos, R=pose[1], units="Meters",
                        length_key=False)
    with pytest.raises(FlightDataError) as e:
        read_raw(path, body="DelFly")
    msg = str(e.value)
    assert "names no Length Units" in msg and "fit neither metres nor millimetres" in msg
    assert "re-export" in msg and "\n" not in msg


OLD_EXPORT = """comment,"OptiTrack Export Data"
info,version,1.1
info,framecount,3
info,rigidbodycount,1
righthanded
rigidbody,1,DelFly,0,0,0,0
frame,0,0.000000,1,1,0.1,0.2,0.3,0,0,0,1,0,0,0
frame,1,0.008333,1,1,0.1,0.2,0.3,0,0,0,1,0,0,0
"""


def _new_header(version="1.23", descriptors=True):
    head = (f"Format Version,{version},Take Name,x,Capture Frame Rate,120.000000,Export Frame "
            "Rate,120.000000,Rotation Type,Quaternion,Length Units,Meters")
    rows = ["", ",Type,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,"
            "Rigid Body", ",Name" + ",A" * 7, ",ID" + ",1" * 7,
            ",,Rotation,Rotation,Rotation,Rotation,Position,Position,Position",
            "Frame,Time (Seconds),X,Y,Z,W,X,Y,Z"]
    if not descriptors:
        rows = rows[:1] + rows[-1:]
    data = [f"{i},{i / 120:.6f},0,0,0,1,0.1,{1 + 1e-3 * i},0" for i in range(20)]
    return "\n".join([head, *rows, *data]) + "\n"


@pytest.mark.parametrize("text, words", [
    (OLD_EXPORT, ["old layout (format version 1.1", "re-export the take from Motive"]),
    (_new_header("1.1"), ["Format Version 1.1", "re-export the take from Motive"]),
    (_new_header(descriptors=False), ["lines 3-7 of the Motive export do not name the columns",
                                      "re-export the take from Motive"]),
])
def test_a_layout_fwid_does_not_read_is_named(tmp_path, capsys, text, words):
    path = tmp_path / "take.csv"
    path.write_text(text)
    rc = main(["reconstruct", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and str(path) in err[0], err
    for w in words:
        assert w in err[0], (w, err[0])


BODIES = ["Right Hand", "Right Forearm", "Right Upper Arm", "Cue Stick", "Cue Ball 1"]


@pytest.mark.parametrize("body", BODIES)
def test_real_export_bodies_are_refused_naming_their_glitches(body):
    """The unedited five-body Motive 1.23 export: every body holds its pose for most frames
    and flips between fits in the rest: refused in one line that counts the flips."""
    path = REAL / "pool_optitrack.csv.gz"
    if not path.is_file():
        pytest.skip(f"the real recordings are not here ({REAL}): see the project's shared data")
    with pytest.raises(FlightDataError) as e:
        read_raw(path, body=body)
    msg = str(e.value)
    assert "\n" not in msg and "tracked frames are glitches" in msg, msg
    flips = int(msg.split(" orientation flips")[0].rsplit("(", 1)[1])
    assert flips >= 30 and "more frames only repeat the previous pose" in msg


def _blank_header(labels: bool) -> str:
    """A format 1.22 Euler export, its descriptor rows with (`labels`) or without `Type`,
    `Name` ... in their first two cells."""
    head = ("Format Version,1.22,Take Name,x,Capture Frame Rate,120.000000,Export Frame "
            "Rate,120.000000,Rotation Type,XYZ,Length Units,Meters,Coordinate Space,Global")
    first = [("Type", "Name", "ID", "") if labels else ("", "", "", "")][0]
    rows = ["", f",{first[0]}" + ",Rigid Body" * 6, f",{first[1]}" + ",A" * 6,
            f",{first[2]}" + ",1" * 6, ",,Rotation,Rotation,Rotation,Position,Position,Position",
            "Frame,Time (Seconds),X,Y,Z,X,Y,Z"]
    data = [f"{i},{i / 120:.6f},{10 + i * 0.5},{-5 + 0.2 * i},{30 - i},0.1,{1 + 1e-3 * i},0.2"
            for i in range(30)]
    return "\n".join([head, *rows, *data]) + "\n"


def test_blank_descriptor_cells_read_as_the_labelled_rows(tmp_path):
    """Motive 1.22's Euler export leaves the first two cells of its Type and Name rows blank:
    read by the rows' places, the same pose as the labelled header's."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "take.csv").write_text(_blank_header(labels=True))
    (tmp_path / "b" / "take.csv").write_text(_blank_header(labels=False))
    a, b = read_raw(tmp_path / "a" / "take.csv"), read_raw(tmp_path / "b" / "take.csv")
    assert b.source == a.source == "Motive CSV export (body A, y-up, Meters, XYZ Euler)"
    np.testing.assert_array_equal(a.pos, b.pos)
    np.testing.assert_array_equal(a.quat, b.quat)
    assert np.allclose(b.pos[5], [0.1, 0.2, -1.005])  # y-up metres to NED


def test_old_optitrack_export_with_comments_is_named(tmp_path, capsys):
    """The old OptiTrack export opens with `comment,"OptiTrack Export Data"` lines (as many
    as the exporter wrote): one line that names it and says how to export a readable take."""
    path = tmp_path / "take.csv"
    path.write_text('comment,"OptiTrack Export Data"\n' + "comment,notes\n" * 14
                    + OLD_EXPORT.split("\n", 1)[1])
    rc = main(["reconstruct", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "old layout (format version 1.1" in err[0] and "re-export the take from Motive" in err[0]
