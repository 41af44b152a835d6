"""The choice of a selection round: an entry built on states' rates gives way to a direct
catalogue explanation, and competes with the probes on its gain otherwise."""

import types

from fwid.diagnose._catalogue import CATALOGUE, get_effect
from fwid.diagnose._probes import PROBES
from fwid.diagnose._selection import RATES_MARGIN, SECONDARY_SHARE, _admissible, tentative


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



def test_a_further_effect_smaller_than_the_first_leaves_is_tentative():
    assert tentative(0.40, 0.9 * SECONDARY_SHARE * 0.40)
    assert not tentative(0.40, 1.1 * SECONDARY_SHARE * 0.40)
