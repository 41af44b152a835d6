"""The choice of a selection round: an entry built on states' rates gives way to a direct
catalogue explanation, and competes with the probes on its gain otherwise."""

import types

from fwid.diagnose._catalogue import CATALOGUE, get_effect
from fwid.diagnose._probes import ATTITUDE_PROBE, PROBES
from fwid.diagnose._selection import RATES_MARGIN, _admissible, _after_the_first


def _ev(**means):
    return {k.replace("_", "-"): types.SimpleNamespace(mean=v) for k, v in means.items()}


def test_only_unsteady_aero_is_built_on_rates_and_probes_are_marked():
    assert [e.name for e in CATALOGUE if e.rates] == ["unsteady-aero"]
    assert all(p.probe for p in PROBES) and not any(e.probe for e in CATALOGUE)


def test_rates_entry_gives_way_to_a_direct_entry_with_half_its_gain():
    un, act, att = get_effect("unsteady-aero"), get_effect("actuator-dynamics"), PROBES[0]
    ev = _ev(unsteady_aero=0.44, actuator_dynamics=0.44 / RATES_MARGIN, attitude=0.2)
    assert _admissible([un, act, att], ev) == [act, att]
    ev = _ev(unsteady_aero=0.44, actuator_dynamics=0.9 * 0.44 / RATES_MARGIN, attitude=0.2)
    assert _admissible([un, act, att], ev) == [un, act, att]
    # probes are no reason to drop it: it then competes with them on its gain
    assert _admissible([un, att], _ev(unsteady_aero=0.1, attitude=0.3)) == [un, att]


def test_after_the_first_effect_a_rates_entry_needs_the_attitude_probe_beside_it():
    un, act = get_effect("unsteady-aero"), get_effect("actuator-dynamics")
    att = next(p for p in PROBES if p.name == ATTITUDE_PROBE)
    drift = next(p for p in PROBES if p.name != ATTITUDE_PROBE)
    # without the attitude probe passing, it is an echo of the first effect's misfit
    assert _after_the_first([un, act, drift]) == [act, drift]
    # with it, the gravity part of the rates is real: it takes the probe's place
    assert _after_the_first([un, att, act]) == [un, act]
    # the probe alone, or neither, is left as it is
    assert _after_the_first([att, act]) == [att, act]
    assert _after_the_first([]) == []
