"""The diagnosis summary in words, on flights that start in their manoeuvre."""

import math

import fwid
from fwid.report import diagnosis_summary
from fwid.synth import write_flights


def test_flights_without_a_steady_start_say_so_not_nan(tmp_path):
    """Flights whose control moves from their first sample (closed-loop flights, or flights
    cut after their first input, as the real Flapper's) have no steady flight for the gap
    map's time split: the summary says so instead of printing 'nanx as large'."""
    def cut(folder, seed):
        write_flights(tmp_path / folder, 2, "lon", seed=seed, effect="none")
        return [f.slice(f.first_input) for f in fwid.load_flights(tmp_path / folder)]

    d = fwid.diagnose(cut("train", 1), cut("test", 2), simulation=False)
    assert all(math.isnan(t["manoeuvre_to_steady"]) for t in d.localisation["by_time"].values())
    text = diagnosis_summary(d)
    assert "nan" not in text.lower()
    assert "no steady flight before the first input" in text


def test_a_disturbance_beside_a_named_effect_is_said(tmp_path):
    """A verdict that stands while a later entry was dropped for tracking a disturbance
    (`disturbance.leaves_red`): the summary names the effect and, beside it, the
    disturbance, with the redness it left; without one, no such line."""
    import dataclasses

    for folder, seed in (("train", 3), ("test", 4)):
        write_flights(tmp_path / folder, 3, "lon", seed=seed, effect="actuator-dynamics")
    d = fwid.diagnose(fwid.load_flights(tmp_path / "train"),
                      fwid.load_flights(tmp_path / "test"), simulation=False)
    assert d.verdict == "actuator-dynamics"
    assert "beside it, a disturbance" not in diagnosis_summary(d)
    red = {**d.disturbance, "leaves_red": {"effects": ["unsteady-aero"], "redness_after": 3.3}}
    text = diagnosis_summary(dataclasses.replace(d, disturbance=red))
    assert "VERDICT: actuator-dynamics" in text
    assert ("beside it, a disturbance: unsteady-aero would cut more of the held-out error but "
            f"leaves it about as red (3.3, from {d.disturbance['redness']:.1f})") in text
