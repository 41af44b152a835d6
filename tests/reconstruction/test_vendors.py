"""Vicon Nexus and Qualisys QTM exports, written here to each vendor's documented layout from
a known pose, read like the fwid raw CSV of the same pose; the real Nexus export in
`../shared/realdata/`; each refusal one line."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fwid import FlightDataError
from fwid.cli import main
from fwid.reconstruction import read_raw
from fwid.synth import write_nexus as nexus, write_qtm_mat as qtm_mat, write_qtm_tsv as qtm_tsv

from .helpers import REAL, Motion, noisy, write_fwid_raw

RATE = 200.0
T = np.arange(0, 2, 1 / RATE)
LOST = (40, 45)
TRACKED = ~((np.arange(len(T)) >= LOST[0]) & (np.arange(len(T)) < LOST[1]))


@pytest.fixture(scope="module")
def pose():
    return noisy(Motion(seed=3), T, np.random.default_rng(1))


@pytest.fixture(scope="module")
def ref(pose, tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    return read_raw(write_fwid_raw(d / "ref.csv", Motion(seed=3), T, pos=pose[0], R=pose[1],
                                   lost=[LOST]))


def _same(a, b, rows=slice(None)):
    assert np.array_equal(a.tracked, b.tracked[rows])
    ok = a.tracked
    assert np.allclose(a.t, b.t[rows], atol=1e-9)
    assert np.max(np.abs(a.pos[ok] - b.pos[rows][ok])) < 2e-6  # written to 1e-3 mm
    assert np.max(1 - np.abs(np.sum(a.quat[ok] * b.quat[rows][ok], 1))) < 1e-8  # 9 decimals
    assert a.dropouts == b.dropouts or rows != slice(None)


def write_nexus(path, pose, euler=None, bodies=("fly:body", "wand:tip")):
    return nexus(path, T, *pose, TRACKED, bodies=bodies, euler=euler)


@pytest.mark.parametrize("euler", [None, "XYZ", "ZYX"])
def test_nexus_reads_like_the_fwid_raw_twin(tmp_path, pose, ref, euler):
    take = read_raw(write_nexus(tmp_path / "take.csv", pose, euler), body="body")
    _same(take, ref)
    assert take.source.startswith("Vicon Nexus CSV export (Segments fly:body, z-up, mm")


def test_nexus_bodies_are_named(tmp_path, pose):
    path = write_nexus(tmp_path / "take.csv", pose)
    for body, words in ((None, "holds fly:body, wand:tip; choose one with --body"),
                        ("arm", "no segment named 'arm' in the Segments block; it holds "
                                "fly:body, wand:tip")):
        with pytest.raises(FlightDataError) as e:
            read_raw(path, body=body)
        assert words in str(e.value) and "\n" not in str(e.value)


def test_a_body_never_tracked_is_named(tmp_path, pose):
    path = write_nexus(tmp_path / "take.csv", pose)
    path.write_text(path.read_text(encoding="utf-8-sig").replace("0,0,0,0,0,0", ",,,,,"))
    rc = main(["reconstruct", str(path), "--out", str(tmp_path / "o"), "--body", "wand:tip",
               "--quiet"])
    assert rc == 2
    with pytest.raises(FlightDataError, match="segment 'wand:tip' is never tracked"):
        read_raw(path, body="tip")


def test_real_nexus_export_reads():
    """The unedited Nexus export of a pendulum rig: 200 Hz, 39315 frames, a pose that stays
    in the room and swings."""
    path = REAL / "vicon_nexus_test_rig.csv.gz"
    if not path.is_file():
        pytest.skip(f"the real recordings are not here ({REAL}): see the project's shared data")
    take = read_raw(path)
    assert take.source.startswith("Vicon Nexus CSV export (Segments test rig:arm, z-up, mm, "
                                  "helical")
    assert abs(1 / take.dt - 200) < 1e-9 and len(take.t) == 39315
    assert take.t[-1] == pytest.approx(196.57)
    ok = take.tracked
    assert ok.sum() > 0.99 * len(ok) and np.all(np.isfinite(take.pos[ok]))
    assert np.all(np.abs(take.pos[ok]) < 1.0)  # metres: within a metre of the lab origin
    angle = 2 * np.degrees(np.arccos(np.clip(np.abs(take.quat[ok, 0]), 0, 1)))
    assert 5 < np.ptp(angle) < 120  # it swings, as a pendulum does
    # the pendulum's arm turns about one lab axis: its rotation vectors keep one direction
    rv = Rotation.from_quat(take.quat[ok][:, [1, 2, 3, 0]]).as_rotvec()
    big = rv[np.linalg.norm(rv, axis=1) > np.radians(8)]
    axis = np.linalg.svd(big, full_matrices=False)[2][0]
    assert np.median(np.abs(big @ axis) / np.linalg.norm(big, axis=1)) > 0.9


def write_qtm_tsv(path, pose, start=1):
    rows = slice(start - 1, None)
    return qtm_tsv(path, T[rows], pose[0][rows], pose[1][rows], TRACKED[rows])


def test_qtm_tsv_reads_like_the_fwid_raw_twin(tmp_path, pose, ref):
    _same(read_raw(write_qtm_tsv(tmp_path / "take.tsv", pose), body="DelFly"), ref)


def test_qtm_trimmed_tsv_starts_at_its_first_frame(tmp_path, pose, ref):
    take = read_raw(write_qtm_tsv(tmp_path / "take.tsv", pose, start=21), body="DelFly")
    assert take.t[0] == pytest.approx(20 / RATE)
    _same(take, ref, slice(20, None))


def _rewrite_qtm(path, change):
    """The QTM TSV at `path` with each tracked row's 16 DelFly cells passed through `change`."""
    lines = path.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("Frame\t"))
    out = lines[:k + 1]
    j = lines[k].split("\t").index("DelFly X")
    for ln in lines[k + 1:]:
        c = ln.split("\t")
        if c[j]:
            c[j:j + 16] = change(c[j:j + 16])
        out.append("\t".join(c))
    path.write_text("\n".join(out) + "\n")
    return path


def _transposed(cells):
    m = np.array(cells[7:16], float).reshape(3, 3).T.ravel()
    return cells[:7] + [repr(float(v)) for v in m]


def test_qtm_rotation_order_matters(tmp_path, pose, ref):
    """The matrix written row by row, beside Euler angles of another definition (here: all
    zero), reads as another attitude: the documented column order holds."""
    path = write_qtm_tsv(tmp_path / "take.tsv", pose)
    take = read_raw(path, body="DelFly")
    swapped = read_raw(_rewrite_qtm(path, lambda c: _transposed(c[:3] + ["0"] * 3 + c[6:])),
                       body="DelFly")
    ok = take.tracked
    assert np.max(1 - np.abs(np.sum(swapped.quat[ok] * ref.quat[ok], 1))) > 0.1
    assert not any("row by row" in w for w in swapped.warnings)


def test_qtm_row_order_told_by_the_euler_angles(tmp_path, pose, ref):
    """The matrix written row by row beside QTM's standard Euler angles is read row by row,
    right, with a warning naming both orders' disagreement."""
    path = _rewrite_qtm(write_qtm_tsv(tmp_path / "take.tsv", pose), _transposed)
    take = read_raw(path, body="DelFly")
    _same(take, ref)
    (note,) = [w for w in take.warnings if "row by row" in w]
    assert "Roll, Pitch, Yaw agree" in note and "QTM's documented order" in note
    assert not any("row by row" in w for w in read_raw(write_qtm_tsv(
        tmp_path / "ok.tsv", pose), body="DelFly").warnings)


def write_qtm_mat(path, pose):
    return qtm_mat(path, T, *pose, TRACKED)


def test_qtm_mat_reads_like_the_fwid_raw_twin(tmp_path, pose, ref):
    take = read_raw(write_qtm_mat(tmp_path / "take.mat", pose), body="DelFly")
    assert take.name == "take" and take.source.startswith("QTM MATLAB export (body DelFly")
    _same(take, ref)


def test_qtm_reconstruction_equals_the_motive_twins(tmp_path, pose):
    """The same pose as a QTM TSV and as a Motive export, neither with an autopilot log:
    `fwid reconstruct` gives the same states."""
    from .helpers import write_motive, write_vehicle

    states = {}
    for form in ("qtm", "motive"):
        d = tmp_path / form
        d.mkdir()
        write_vehicle(d)
        if form == "qtm":
            write_qtm_tsv(d / "take.tsv", pose)
        else:
            write_motive(d / "take.csv", Motion(seed=3), T, pos=pose[0], R=pose[1], log=False,
                         lost=[LOST])
        out = tmp_path / f"{form}-out"
        assert main(["reconstruct", str(d), "--out", str(out), "--body", "DelFly",
                     "--keep-ground", "--quiet"]) == 0
        states[form] = np.genfromtxt(out / "take.csv", delimiter=",", names=True)
    a, b = states["qtm"], states["motive"]
    assert len(a) == len(b) > 300
    for c in ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi"):
        assert np.max(np.abs(a[c] - b[c])) < 1e-4 * (1 + np.max(np.abs(b[c])))  # 0.01 %: rounding, c
