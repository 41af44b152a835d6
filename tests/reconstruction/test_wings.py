"""The flapping frequency from a take's tracked wings (rigid bodies of their own)."""

import numpy as np
from scipy.spatial.transform import Rotation

from fwid.reconstruction import read_raw
from fwid.reconstruction._wings import beat_frequency, stroke_angle

from .helpers import C_YUP, Motion, noisy, write_vehicle

T = np.arange(0, 6, 1 / 120)  # a 120 Hz take


def _f(t):
    return 11.0 + 2.0 * t / t[-1]  # the beat speeds up from 11 to 13 Hz


def write_winged_take(path, motion, t):
    """A Motive export (y-up, metres, quaternions, no log) of a body `Flapper` and two wings
    that swing +-40 deg about the body's x axis at the beat `_f`."""
    pos, R = noisy(motion, t, np.random.default_rng(0))
    phase = 2 * np.pi * np.cumsum(_f(t)) * (t[1] - t[0])
    bodies = [("Flapper", R)]
    for side, sign in (("FlapperLeftWing", 1.0), ("FlapperRightWing", -1.0)):
        swing = Rotation.from_rotvec(np.outer(sign * np.deg2rad(40) * np.sin(phase), [1, 0, 0]))
        bodies.append((side, R @ swing.as_matrix()))
    n = len(t)
    head = ("Format Version,1.23,Take Name,w,Capture Frame Rate,120.000000,Export Frame Rate,"
            f"120.000000,Total Frames in Take,{n},Rotation Type,Quaternion,Length Units,Meters")
    types, names, groups, axes, cols = [], [], [], [], [np.arange(n), t]
    for name, Rb in bodies:
        q = Rotation.from_matrix(C_YUP.T @ Rb @ C_YUP).as_quat()  # x y z w, y-up
        p = pos @ C_YUP
        for g, letters, vals in (("Rotation", "XYZW", q.T), ("Position", "XYZ", p.T)):
            for a, v in zip(letters, vals):
                types.append("Rigid Body")
                names.append(name)
                groups.append(g)
                axes.append(a)
                cols.append(v)
    lines = [head, "", ",Type," + ",".join(types), ",Name," + ",".join(names),
             ",ID," + ",".join("1" for _ in types), ",," + ",".join(groups),
             "Frame,Time (Seconds)," + ",".join(axes)]
    data = np.column_stack(cols)
    lines += [f"{int(r[0])},{r[1]:.6f}," + ",".join(f"{v:.9f}" for v in r[2:]) for r in data]
    path.write_text("\n".join(lines) + "\n")
    write_vehicle(path.parent)
    return path


def test_beat_frequency_of_a_chirp():
    t = np.arange(0, 4, 0.005)
    angle = 0.5 * np.sin(2 * np.pi * np.cumsum(_f(t)) * 0.005)
    f = beat_frequency(t, angle)
    inner = slice(40, -40)
    np.testing.assert_allclose(f[inner], _f(t)[inner], atol=0.15)
    assert beat_frequency(t, 0.01 * np.random.default_rng(1).standard_normal(len(t))) is None


def test_stroke_angle_is_the_swing_about_the_hinge():
    R = Motion(seed=1).R(T)
    swing = Rotation.from_rotvec(np.outer(0.3 * np.sin(2 * np.pi * 12 * T), [1, 0, 0]))
    a = stroke_angle(R, R @ swing.as_matrix(), np.ones(len(T), bool))
    ref = 0.3 * np.sin(2 * np.pi * 12 * T)
    assert abs(abs(np.corrcoef(a, ref)[0, 1]) - 1) < 1e-9


def test_winged_take_gives_the_flapping_frequency(tmp_path):
    """A tracking-only Motive take with two wing bodies: `f` from the wings, said so."""
    take = read_raw(write_winged_take(tmp_path / "w.csv", Motion(seed=3), T), body="Flapper")
    assert take.onboard is None
    f = take.controls["f"]
    inner = slice(60, -60)
    np.testing.assert_allclose(f[inner], _f(take.t)[inner], atol=0.2)
    assert any("tracked wings (FlapperLeftWing, FlapperRightWing)" in w for w in take.warnings)


def test_winged_take_reconstructs_with_its_f(tmp_path):
    import fwid

    res = fwid.reconstruct(write_winged_take(tmp_path / "w.csv", Motion(seed=3), T),
                           body="Flapper")
    assert not res.failures, res.failures
    c = res.flights[0].columns
    assert abs(np.median(c["f"]) - 12.0) < 0.2 and "de" not in c
