"""The raw readers: both forms to north-east-down, and every bad input a one-line error with
exit code 2 through the command line, before any smoothing."""

import numpy as np
import pytest

from fwid import FlightDataError
from fwid.cli import main
from fwid.reconstruction import read_raw

from .helpers import Motion, write_fwid_raw, write_motive

T = np.arange(0, 4, 0.005)


@pytest.fixture(scope="module")
def motion():
    return Motion(seed=1)


def test_motive_y_up_millimetres_equals_ned_twin(tmp_path, motion):
    """The same recorded pose written as a fwid raw CSV in NED and as a Motive y-up
    export in millimetres (6 decimals, a second rigid body) reads the same."""
    rng = np.random.default_rng(0)
    from .helpers import noisy
    pos, R = noisy(motion, T, rng)
    a = read_raw(write_fwid_raw(tmp_path / "a.csv", motion, T, pos=pos, R=R, lost=[(50, 55)]))
    (tmp_path / "m").mkdir()
    b = read_raw(write_motive(tmp_path / "m" / "a.csv", motion, T, pos=pos, R=R,
                              lost=[(50, 55)]), body="DelFly")
    assert np.array_equal(a.tracked, b.tracked) and a.dropouts == b.dropouts
    ok = a.tracked
    assert np.max(np.abs(a.pos[ok] - b.pos[ok])) < 1e-9  # 6 decimals of a millimetre
    dots = np.abs(np.sum(a.quat[ok] * b.quat[ok], 1))
    assert np.max(1 - dots) < 1e-10
    # sign continuity: no sign change between neighbours
    assert np.all(np.sum(b.quat[ok][1:] * b.quat[ok][:-1], 1) > 0)
    assert b.onboard is not None and set("pqr") <= set(b.onboard.columns)


def _edit_line(path, k, fn):
    lines = path.read_text().splitlines()
    lines[k] = fn(lines[k])
    path.write_text("\n".join(lines) + "\n")


def _motive(tmp_path, motion, **kw):
    return write_motive(tmp_path / "take.csv", motion, T, **kw)


def _fwid(tmp_path, motion, **kw):
    return write_fwid_raw(tmp_path / "take.csv", motion, T, **kw)


def _euler_fwid(tmp_path, motion):
    p = _fwid(tmp_path, motion)
    _edit_line(p, 0, lambda s: s.replace("qw,qx,qy,qz", "phi,theta,psi,extra"))
    return p, []


def _bad_norm(tmp_path, motion):
    p = _fwid(tmp_path, motion)
    _edit_line(p, 41, lambda s: ",".join(c if i != 4 else str(float(c) * 1.01)
                                         for i, c in enumerate(s.split(","))))
    return p, []


def _uneven(tmp_path, motion):
    p = _fwid(tmp_path, motion)
    _edit_line(p, 101, lambda s: ",".join([str(float(s.split(",")[0]) + 0.002)] + s.split(",")[1:]))
    return p, []


CASES = {
    "rotation-type": (lambda tp, m: (_motive(tp, m, rotation="Matrix"), ["--body", "DelFly"]),
                      ["Rotation Type 'Matrix'", "Rotation Type = Quaternion"]),
    "euler-fwid": (_euler_fwid, ["Euler", "qw qx qy qz"]),
    "unknown-body": (lambda tp, m: (_motive(tp, m), ["--body", "Bee"]),
                     ["'Bee'", "Wand, DelFly", "--body"]),
    "two-bodies": (lambda tp, m: (_motive(tp, m), []), ["Wand, DelFly", "--body NAME"]),
    "no-such-log": (lambda tp, m: (_motive(tp, m, log=False),
                                   ["--body", "DelFly", "--onboard", str(tp / "nope.csv")]),
                    ["nope.csv", "no such autopilot log"]),
    "non-unit": (_bad_norm, ["line 42", "norm", "qw qx qy qz"]),
    "long-dropout": (lambda tp, m: (_fwid(tp, m, lost=[(100, 150)]), []),
                     ["0.25 s", "t = 0.5", "--max-dropout"]),
    "uneven": (_uneven, ["line 102", "not uniform", "resample"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input_message_and_exit_code(tmp_path, motion, capsys, case):
    make, words = CASES[case]
    path, extra = make(tmp_path, motion)
    rc = main(["reconstruct", str(path), "--out", str(tmp_path / "out"), "--quiet", *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and str(path) in err[0], err
    for w in words:
        assert w in err[0], (w, err[0])
    assert not (tmp_path / "out" / "take.csv").exists()


def test_read_raw_refuses_the_same(tmp_path, motion):
    with pytest.raises(FlightDataError, match="Rotation Type 'Matrix' unknown"):
        read_raw(_motive(tmp_path, motion, rotation="Matrix"), body="DelFly")


def test_bad_take_is_answered_before_jax(tmp_path, motion):
    """A take refused while reading never imports JAX (the answer comes at once)."""
    import subprocess
    import sys

    path = _fwid(tmp_path, motion, lost=[(100, 150)])
    probe = ("import sys\nfrom fwid.cli import main\nrc = main(sys.argv[1:])\n"
             "print('jax' in sys.modules)\nsys.exit(rc)")
    res = subprocess.run([sys.executable, "-c", probe, "reconstruct", str(path), "--out",
                          str(tmp_path / "out"), "--quiet"], capture_output=True, text=True)
    assert res.returncode == 2 and res.stdout.strip().endswith("False"), res


def test_gzip_take_reads_like_the_plain_one(tmp_path):
    """A take compressed with gzip (`NAME.csv.gz`) is found in a folder and read like the
    plain file; its name drops both suffixes."""
    import gzip

    from fwid.reconstruction import raw_files, read_raw

    rng = np.random.default_rng(0)
    n = 50
    t = np.arange(n) * 0.01
    rows = ["t,x,y,z,qw,qx,qy,qz,de,dr,f"]
    for k in range(n):
        rows.append(f"{t[k]:.4f},{rng.normal():.6f},0,-1,1,0,0,0,0.01,0,12")
    text = "\n".join(rows) + "\n"
    (tmp_path / "plain.csv").write_text(text)
    with gzip.open(tmp_path / "packed.csv.gz", "wt") as fh:
        fh.write(text)
    assert [p.name for p in raw_files(tmp_path)] == ["packed.csv.gz", "plain.csv"]
    a, b = read_raw(tmp_path / "plain.csv"), read_raw(tmp_path / "packed.csv.gz")
    assert b.name == "packed" and a.name == "plain"
    np.testing.assert_array_equal(a.pos, b.pos)


def test_motive_take_without_log_is_tracking_only(tmp_path):
    """A Motive take with no autopilot log beside it is read from the pose alone: no
    controls, no log, and a warning that says so."""
    take = read_raw(_motive(tmp_path, Motion(seed=1), log=False), body="DelFly")
    assert take.onboard is None and take.controls is None
    assert any("no autopilot log" in w for w in take.warnings), take.warnings
