"""The airborne cut (`fwid.reconstruction._airborne`): rests on the ground found from the pose,
the flight kept from where it clears its rest height to where it last does, split at tracking
losses too long to bridge; nothing cut on fwid's own simulated takes."""

import numpy as np
import pytest

from fwid import FlightDataError
from fwid.reconstruction import read_raw
from fwid.reconstruction._raw import RawTake
from fwid.reconstruction._airborne import CLEARANCE, MIN_AIRBORNE, airborne, cut_take
from fwid.synth import write_raw_flights

DT = 0.01
T = np.arange(0.0, 40.0, DT)
REST0, REST1 = -0.06, -0.09  # NED: 6 and 9 cm up
UP, DOWN = (8.0, 10.0), (30.0, 32.0)  # lift-off and touch-down ramps (s)
TOP = -1.5


def _ramp(t, a, b, z0, z1):
    s = np.clip((t - a) / (b - a), 0, 1)
    return z0 + (z1 - z0) * 0.5 * (1 - np.cos(np.pi * s))


def _cross(a, b, z0, z1, rising: bool):
    """When the ramp from z0 to z1 over (a, b) is CLEARANCE from its rest end."""
    frac = CLEARANCE / abs(z1 - z0)
    s = np.arccos(1 - 2 * frac) / np.pi if rising else 1 - np.arccos(1 - 2 * frac) / np.pi
    return a + s * (b - a)


def _profile(seed=0):
    """Rest, lift-off, 20 s of flight, touch-down, rest; 0.5 mm tracking noise."""
    rng = np.random.default_rng(seed)
    z = np.where(T < 20, _ramp(T, *UP, REST0, TOP), _ramp(T, *DOWN, TOP, REST1))
    fly = (T > UP[1]) & (T < DOWN[0])
    z = z + np.where(fly, 0.3 * np.sin(2 * np.pi * 0.2 * (T - UP[1])), 0.0)
    x = np.where(fly, 0.4 * np.sin(2 * np.pi * 0.3 * (T - UP[1])), 0.0)
    pos = np.stack([x, 0.0 * x, z], 1) + rng.normal(0, 5e-4, (len(T), 3))
    return pos, np.ones(len(T), bool)


def test_rest_flight_rest_is_cut_at_lift_off_and_touch_down():
    pos, tracked = _profile()
    air = airborne(T, pos, tracked, max_dropout=0.1, path="take.csv")
    t0, t1 = T[air.keep][0], T[air.keep][-1]
    assert abs(t0 - _cross(*UP, REST0, TOP, True)) < 2 * DT, t0
    assert abs(t1 - _cross(*DOWN, TOP, REST1, False)) < 2 * DT, t1
    (g0, g1), (g2, g3) = air.ground
    assert g0 == 0.0 and 7.5 <= g1 < t0 and t1 < g2 <= 32.5 and g3 == pytest.approx(T[-1])
    assert air.others == [] and air.gaps == []
    (note,) = air.warnings
    assert f"cut to t = {t0:.6g} to {t1:.6g} s" in note and "--keep-ground" in note


def test_keep_ground_keeps_the_record_and_names_the_rests():
    pos, tracked = _profile()
    air = airborne(T, pos, tracked, max_dropout=0.1, keep_ground=True)
    assert air.keep == slice(0, len(T))
    assert len(air.ground) == 2 and "on the ground" in air.warnings[0]
    assert "kept (--keep-ground)" in air.warnings[0]


def test_wings_at_rest_are_cut_even_when_the_ground_is_kept():
    pos, tracked = _profile()
    f = np.where((T > 5) & (T < 35), 12.0, 0.0)
    air = airborne(T, pos, tracked, f, max_dropout=0.1, keep_ground=True)
    assert T[air.keep][0] == pytest.approx(5.01) and T[air.keep][-1] == pytest.approx(34.99)


def test_a_long_tracking_loss_splits_the_take_and_a_short_stretch_is_left_out():
    pos, tracked = _profile()
    tracked = tracked & ~((T >= 12.0) & (T < 12.5))
    pos[~tracked] = np.nan
    air = airborne(T, pos, tracked, max_dropout=0.1)
    assert T[air.keep][0] == pytest.approx(12.5) and T[air.keep][-1] > 30.0
    assert len(air.others) == 1 and air.others[0][1] == pytest.approx(11.99)
    assert air.more == []
    assert air.gaps == [[12.0, pytest.approx(12.49)]]
    assert "left out: t = " in air.warnings[1] and "lost for longer than the 0.1 s" in air.warnings[1]
    whole = airborne(T, pos, tracked, max_dropout=1.0)  # bridged: one stretch
    assert whole.others == [] and T[whole.keep][0] < 10.0


def test_a_take_with_no_stretch_long_enough_is_refused():
    pos, tracked = _profile()
    for a in (12.0, 16.0, 20.0, 24.0, 28.0):
        tracked &= ~((T >= a) & (T < a + 0.5))
    pos[~tracked] = np.nan
    with pytest.raises(FlightDataError) as e:
        airborne(T, pos, tracked, max_dropout=0.1, path="take.csv")
    msg = str(e.value)
    assert msg.startswith("take.csv: the body is lost for 0.5 s from t = 12 s")
    assert "under the 5 s" in msg and "--max-dropout" in msg and "\n" not in msg


def test_a_take_that_never_lifts_off_is_refused_naming_keep_ground():
    rng = np.random.default_rng(1)
    pos = np.array([0.0, 0.0, REST0]) + rng.normal(0, 5e-4, (len(T), 3))
    with pytest.raises(FlightDataError, match="no airborne stretch is left.*--keep-ground"):
        airborne(T, pos, np.ones(len(T), bool), max_dropout=0.1, path="bench.csv")


@pytest.mark.parametrize("raw", ["fwid", "motive"])
def test_nothing_is_cut_on_simulated_takes(tmp_path, raw):
    (path,) = write_raw_flights(tmp_path, raw=raw, n_flights=1, seed=3)
    take = read_raw(path, body="DelFly" if raw == "motive" else None, max_dropout=np.inf)
    ((cut, _),), air = cut_take(take, max_dropout=0.1)
    assert len(cut.t) == len(take.t) and air.ground == [] and air.warnings == []
    assert cut.name == take.name and cut.stretch == {"t_s": [take.t[0], take.t[-1]],
                                                     "part": 1, "of": 1}


def _two_stretches():
    """The flight lost from t = 15 to 23 s: airborne about 8.5-15 s and 23-31.5 s."""
    pos, tracked = _profile()
    tracked = tracked & ~((T >= 15.0) & (T < 23.0))
    pos[~tracked] = np.nan
    return pos, tracked


def test_each_stretch_long_enough_becomes_a_flight_of_its_own():
    pos, tracked = _two_stretches()
    air = airborne(T, pos, tracked, max_dropout=0.1, path="take.csv", name="take")
    (second,) = air.more  # the earlier, shorter stretch: take_2
    first = air.keep  # the longest, after the loss, keeps the name
    assert T[first][0] == pytest.approx(23.0) and T[first][-1] > 31.0
    assert T[second][0] < 9.0 and T[second][-1] == pytest.approx(14.99)
    assert T[second][-1] - T[second][0] >= MIN_AIRBORNE and air.others == []
    (note,) = [w for w in air.warnings if "gives 2 flights" in w]
    assert "(take.csv)" in note and "to 14.99 s (take_2.csv)" in note
    assert "lost for longer than the 0.1 s bridged (t = 15 to 22.99 s)" in note
    # bridged: one flight again
    assert airborne(T, pos, tracked, max_dropout=9.0).more == []


def test_cut_take_names_the_flights_and_their_stretches():
    pos, tracked = _two_stretches()
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (len(T), 1))
    take = RawTake("lon_0", "lon_0.csv", "fwid raw CSV", "NED", T, pos, quat, tracked, None,
                   None, [[15.0, 22.99]], ["a warning of the take"])
    (a, fa), (b, fb) = cut_take(take, np.full(len(T), 12.0), max_dropout=0.1)[0]
    assert (a.name, b.name) == ("lon_0", "lon_0_2")
    assert a.stretch["part"] == 2 and b.stretch["part"] == 1 and a.stretch["of"] == 2
    assert a.stretch["t_s"][0] == pytest.approx(23.0)
    assert b.stretch["t_s"][1] == pytest.approx(14.99)
    assert a.warnings[0] == b.warnings[0] == "a warning of the take"
    assert len(fa) == len(a.t) and len(fb) == len(b.t) and a.dropouts == b.dropouts == []
    assert any("gives 2 flights" in w for w in a.warnings + b.warnings)
    # another take of the run is named lon_0_2: the stretch takes a name of its own
    (a, _), (b, _) = cut_take(take, None, max_dropout=0.1, taken={"lon_0_2"})[0]
    assert (a.name, b.name) == ("lon_0", "lon_0_stretch2")
    assert any("(lon_0_stretch2.csv)" in w for w in b.warnings)
