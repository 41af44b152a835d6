"""`fwid reconstruct` on exact nonlinear manoeuvres with optical noise: frames, quaternion
signs, the clock offset, the flapping content, bad takes among good ones."""

import json

import numpy as np
import pytest

import fwid
from fwid.cli import main
from fwid.reconstruction._model import phase_of
from fwid.reconstruction._smoother import smooth_batch

from .helpers import F0, Motion, noisy, write_fwid_raw, write_motive

T = np.arange(0, 4, 0.005)  # 200 Hz; every take here has this length (one compilation)
STATES = ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi", "X", "Y", "Z", "L", "M", "N")


@pytest.fixture(scope="module")
def motion():
    return Motion(seed=2)


@pytest.fixture(scope="module")
def pose(motion):
    return noisy(motion, T, np.random.default_rng(7))


def _one(path, **kw):
    res = fwid.reconstruct(path, **kw)
    assert not res.failures, res.failures
    return res.flights[0]


def _rel(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.std(b))


def test_y_up_twin_and_sign_flips_give_the_same_states(tmp_path, motion, pose):
    pos, R = pose
    for name, kw in (("ned", {}), ("yup", {"frame": "y-up"}), ("noflip", {"flip": False})):
        (tmp_path / name).mkdir()
        write_fwid_raw(tmp_path / name / "a.csv", motion, T, pos=pos, R=R, lost=[(300, 310)], **kw)
    ned = _one(tmp_path / "ned")
    yup = _one(tmp_path / "yup", frame="y-up")
    same = _one(tmp_path / "noflip")
    for k in STATES:
        scale = np.max(np.abs(ned.columns[k]))
        assert np.max(np.abs(yup.columns[k] - ned.columns[k])) < 1e-7 * scale, k
        assert np.max(np.abs(same.columns[k] - ned.columns[k])) < 1e-7 * scale, k
    # and it is right: states against the exact motion, away from the ends
    c, s = ned.columns, slice(40, -40)
    V, w = motion.V(T), motion.w(T)
    for i, k in enumerate("uvw"):
        assert _rel(c[k][s], V[s, i]) < 0.03, k
    for i, k in enumerate("pq"):
        assert _rel(c[k][s], w[s, i]) < 0.1, k
    assert ned.entry["dropouts"] == [[1.5, 1.545]]
    assert 2e-4 < ned.entry["noise"]["position_m"] < 6e-4  # 0.4 mm, from the innovations


def test_clock_offset_found_within_1ms(tmp_path, motion, pose):
    pos, R = pose
    write_motive(tmp_path / "m.csv", motion, T, pos=pos, R=R, offset=-133.0123, log_rate=500.0)
    fl = _one(tmp_path / "m.csv", body="DelFly")
    e = fl.entry
    assert abs(e["clock_offset_s"] - (-133.0123)) < 1e-3
    assert e["clock"]["corr"] > 0.9 and e["clock"]["std_s"] < 1e-3
    assert np.allclose(e["gyro_bias_rad_s"], [0.02, -0.03, 0.01], atol=5e-3)
    # with the gyro the moments come through: M within 15 % of its spread
    _, M = motion.loads(fl.columns["t"])
    assert _rel(fl.columns["M"][40:-40], M[40:-40, 1]) < 0.15
    given = _one(tmp_path / "m.csv", body="DelFly", clock_offset=-133.0)
    assert given.entry["clock"]["given"] and given.entry["clock_offset_s"] == -133.0


def test_36_hz_acceleration_survives():
    """The 3rd flapping harmonic (36 Hz at 12 Hz flapping) of the acceleration comes through
    the smoother with < 10 % amplitude loss at 200 Hz and 0.4 mm noise."""
    rng = np.random.default_rng(3)
    A, w3 = 30.0, 2 * np.pi * 3 * F0
    slow = 0.3 * np.sin(2 * np.pi * 0.5 * T)
    pos = slow - A / w3**2 * np.sin(w3 * T + 0.4) + 0.8 * T
    z = pos[:, None] + 4e-4 * rng.standard_normal((len(T), 3))
    ph, om = phase_of(np.full(len(T), F0), 0.005)
    sm = smooth_batch(z[None], np.ones((1, len(T)), bool), ph[None], om[None], 0.005)
    X = np.stack([np.sin(w3 * T), np.cos(w3 * T), np.ones_like(T), np.sin(2 * np.pi * 0.5 * T)], 1)
    for i in range(3):
        amp = np.hypot(*np.linalg.lstsq(X[40:-40], sm.acc[0, 40:-40, i], rcond=None)[0][:2])
        assert abs(amp / A - 1) < 0.1, amp


def test_bad_take_among_good_ones(tmp_path, motion, pose, capsys):
    """A folder with a good take and a bad one (a dropout too long): the good one is
    written, the bad one reported, exit 2, and a flight already in the output folder is kept."""
    pos, R = pose
    raw = tmp_path / "raw"
    raw.mkdir()
    write_fwid_raw(raw / "good.csv", motion, T, pos=pos, R=R)
    write_fwid_raw(raw / "lost.csv", motion, T, pos=pos, R=R, lost=[(100, 200)])
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.csv").write_text("t\n0\n")
    (out / "reconstruction.json").write_text(json.dumps({"flights": [{"flight": "earlier.csv"}]}))
    rc = main(["reconstruct", str(raw), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    bad = [ln for ln in err if ln.startswith("fwid: error:")]
    assert len(bad) == 1 and "lost.csv" in bad[0] and "--max-dropout" in bad[0], err
    assert any("good: 800 samples" in ln for ln in err), err  # the progress line
    assert (out / "good.csv").is_file() and not (out / "lost.csv").exists()
    assert (out / "good.reconstruction.png").is_file()
    assert (out / "earlier.csv").read_text() == "t\n0\n"
    rep = json.loads((out / "reconstruction.json").read_text())
    assert [e["flight"] for e in rep["flights"]] == ["earlier.csv", "good.csv"]
    flights = fwid.load_flights(out / "good.csv")
    assert flights[0].t.shape == (len(T),)


def test_frame_that_contradicts_the_data(tmp_path, motion, pose, capsys):
    """A z-up world (aircraft body axes) read as north-east-down: gravity is subtracted
    along the wrong axis and the mean aerodynamic force points down the body."""
    pos, R = pose
    Z = np.diag([1.0, -1.0, -1.0])
    p = write_fwid_raw(tmp_path / "upside.csv", motion, T, pos=pos @ Z, R=Z @ R)
    rc = main(["reconstruct", str(p), "--out", str(tmp_path / "out"), "--quiet"])
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert rc == 2 and "reconstructed 0 of 1 takes" in cap.out
    assert len(err) == 1 and "upside.csv" in err[0] and "--frame" in err[0], err
    assert "down the body" in err[0]


def test_too_short_overlap(tmp_path, motion, pose, capsys):
    pos, R = pose
    p = write_motive(tmp_path / "m.csv", motion, T, pos=pos, R=R, offset=0.0)
    log = p.with_name("m.onboard.csv")
    lines = log.read_text().splitlines()
    log.write_text("\n".join(lines[:600]) + "\n")  # 1.2 s of log
    rc = main(["reconstruct", str(p), "--out", str(tmp_path / "out"), "--body", "DelFly",
               "--clock-offset", "0", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "overlap" in err[0] and "m.csv" in err[0], err




def test_wrong_frame_named_by_the_gyro(tmp_path, motion, pose, capsys):
    """A Motive take (y-up) read as z-up: its autopilot's gyro agrees with the rates of the
    y-up reading, and the message names that frame."""
    pos, R = pose
    p = write_motive(tmp_path / "m.csv", motion, T, pos=pos, R=R)
    rc = main(["reconstruct", str(p), "--out", str(tmp_path / "out"), "--quiet",
               "--frame", "z-up", "--no-figures", "--body", "DelFly"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "gyro" in err[0] and "--frame y-up" in err[0], err
    assert main(["reconstruct", str(p), "--out", str(tmp_path / "ok"), "--quiet",
                 "--no-figures", "--body", "DelFly"]) == 0


def test_gyro_follows_names_a_log_s_gyro_and_a_map_s_in_the_take():
    """The first attitude pass skips the ends' prior exactly where a gyro pass follows: a log
    with `p q r`, or a map's `p_gyro ..` in the take; a fwid raw CSV's `p q r` are no gyro."""
    from types import SimpleNamespace as NS

    from fwid.reconstruction._pipeline import _gyro_follows

    pqr = dict.fromkeys("pqr", 0.0)
    assert _gyro_follows(NS(onboard=NS(columns={"de": 0.0, **pqr}), controls=None))
    assert not _gyro_follows(NS(onboard=NS(columns={"de": 0.0}), controls=None))
    assert _gyro_follows(NS(onboard=None, controls={f"{k}_gyro": 0.0 for k in "pqr"}))
    assert not _gyro_follows(NS(onboard=None, controls={"de": 0.0, **pqr}))
    assert not _gyro_follows(NS(onboard=None, controls=None))
