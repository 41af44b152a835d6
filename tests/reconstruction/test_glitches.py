"""Glitches: held poses, orientation flips and position jumps are found (none on a clean
take), dropped and named; a take with too many is refused in one line."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fwid import FlightDataError
from fwid.reconstruction import read_raw
from fwid.reconstruction._glitches import drop_glitches

from .helpers import Motion, noisy, quats, write_fwid_raw

RATE = 120.0


def _take(seconds=60.0, seed=0, scale=1.5):
    """A fast manoeuvre (body rates of several rad/s) at 120 Hz, with tracking noise."""
    t = np.arange(0, seconds, 1 / RATE)
    rng = np.random.default_rng(seed)
    pos, R = noisy(Motion(scale=scale, seed=seed), t, rng)
    return t, pos, R, rng


def _flip(R, rows, rng):
    """`R` with the samples `rows` turned 150-180 deg about a random axis (a rigid body
    fitted the wrong way round)."""
    R = R.copy()
    ax = rng.standard_normal((len(rows), 3))
    ax *= rng.uniform(np.deg2rad(150), np.pi, (len(rows), 1)) / np.linalg.norm(ax, axis=1)[:, None]
    R[rows] = R[rows] @ Rotation.from_rotvec(ax).as_matrix()
    return R


def test_clean_fast_take_loses_nothing():
    t, pos, R, rng = _take()
    q = quats(R, True, rng)
    tracked, warnings = drop_glitches(t, q, np.ones(len(t), bool), pos)
    assert tracked.all() and warnings == []


def test_hundreds_of_flips_are_found_exactly_and_named():
    t, pos, R, rng = _take()
    singles = rng.choice(np.arange(10, len(t) - 10, 20), 240, replace=False)
    runs = np.concatenate([np.arange(a, a + 3) for a in (1001, 3003, 5005)])  # 3-frame flips
    rows = np.sort(np.concatenate([singles, runs]))
    q = quats(_flip(R, rows, rng), True, rng)
    lost = np.zeros(len(t), bool)
    lost[2000:2005] = True  # a dropout: the walk goes across it
    q[lost], p = np.nan, pos.copy()
    p[lost] = np.nan
    p[4000] += [0.5, 0.0, 0.0]  # markers swapped: a position jump of 0.5 m in one frame
    tracked, warnings = drop_glitches(t, q, ~lost, p, "take.csv")
    dropped = np.flatnonzero(~tracked & ~lost)
    assert np.array_equal(dropped, np.sort(np.concatenate([rows, [4000]])))
    assert len(warnings) == 2, warnings
    assert warnings[0].startswith(f"{rows.size} orientation glitches (flips) dropped, at t = ")
    assert warnings[0].startswith(f"{rows.size} orientation glitches (flips) dropped, at t = "
                                  f"{t[rows[0]]:.4g}, ")
    assert warnings[1].startswith("1 position jump (markers swapped) dropped, at t = 33.33 s")


def test_a_take_that_starts_on_a_flip_is_followed_from_its_longest_stretch():
    t, pos, R, rng = _take(seconds=10.0)
    q = quats(_flip(R, np.arange(0, 4), rng), False, rng)
    tracked, _ = drop_glitches(t, q, np.ones(len(t), bool))
    assert np.array_equal(np.flatnonzero(~tracked), np.arange(4))


def test_too_many_glitches_are_refused_in_one_line():
    t, pos, R, rng = _take(seconds=20.0)
    rows = np.arange(5, len(t) - 5, 8)  # one frame in eight
    q = quats(_flip(R, rows, rng), True, rng)
    with pytest.raises(FlightDataError) as e:
        drop_glitches(t, q, np.ones(len(t), bool), pos, "take.csv")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"take.csv: {rows.size} of {len(t)} tracked frames")
    assert f"{rows.size} orientation flips" in msg and "re-create the rigid body" in msg


def test_held_poses_are_dropped_and_said():
    t, pos, R, rng = _take(seconds=5.0)
    q = quats(R, False, rng)
    q[101:104], pos[101:104] = q[100], pos[100]  # the tracking held frame 100's pose
    tracked, warnings = drop_glitches(t, q, np.ones(len(t), bool), pos)
    assert np.array_equal(np.flatnonzero(~tracked), [101, 102, 103])
    assert warnings == ["3 frames repeat the previous frame's pose exactly (a value the "
                        "tracking held, not a measurement): dropped as dropouts, at t = "
                        f"{t[101]:.4g}-{t[103]:.4g} s"]


def test_fwid_raw_reader_drops_flips(tmp_path):
    """The fwid raw CSV reader calls the same function: the flipped rows are dropouts."""
    t, pos, R, rng = _take(seconds=4.0)
    rows = np.array([100, 200, 201, 350])
    path = write_fwid_raw(tmp_path / "take.csv", Motion(), t, pos=pos, R=_flip(R, rows, rng))
    take = read_raw(path)
    assert np.array_equal(np.flatnonzero(~take.tracked), rows)
    assert take.dropouts == [[t[100], t[100]], [t[200], t[201]], [t[350], t[350]]]
    assert take.warnings[0].startswith("4 orientation glitches (flips) dropped")


def test_flipped_take_reconstructs_with_the_clean_rates(tmp_path):
    """One frame in 30 flipped by 171 deg: the reconstruction names the flips, and its body
    rates are the clean take's (not the thousands of deg/s the flips would make)."""
    from fwid.reconstruction import reconstruct

    t = np.arange(0, 6, 1 / 200.0)
    motion, rng = Motion(seed=3), np.random.default_rng(0)
    pos, R = noisy(motion, t, rng)
    rows = np.arange(7, len(t) - 7, 30)
    flipped = R.copy()
    flipped[rows] = R[rows] @ Rotation.from_rotvec([0.95 * np.pi, 0, 0]).as_matrix()
    paths = []
    for name, RR in (("clean", R), ("flips", flipped)):
        (tmp_path / name).mkdir()
        paths.append(write_fwid_raw(tmp_path / name / "take.csv", motion, t, pos=pos, R=RR))
    res = reconstruct(paths, processes=0)
    assert res.failures == []
    clean, flips = res.flights
    assert clean.entry["warnings"] == []
    assert flips.entry["warnings"][0].startswith(f"{rows.size} orientation glitches (flips) "
                                                 f"dropped, at t = {t[7]:.4g}, {t[37]:.4g}")
    w = [np.stack([f.columns[k] for k in "pqr"], 1) for f in (clean, flips)]
    true = motion.w(t)
    assert np.max(np.abs(w[1])) < 1.05 * np.max(np.abs(true))
    assert np.sqrt(np.mean((w[1] - w[0]) ** 2)) < 0.05 * np.sqrt(np.mean(true**2))
