"""The choice of a selection round: an entry built on states' rates gives way to a direct
catalogue explanation, and competes with the probes on its gain otherwise."""

import types

from fwid.diagnosis._catalogue import CATALOGUE, get_effect
from fwid.diagnosis._probes import PROBES
from fwid.diagnosis import _selection
from fwid.diagnosis._selection import RATES_MARGIN, _admissible


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


def test_each_round_adds_the_largest_gain_that_passes(monkeypatch):
    """Round 1: three pass, the largest gain is chosen (not the one that failed the level);
    round 2: the only one that passes; round 3: none passes and the selection stops."""
    import math

    table = {(): {"flap-coupling": (1e-6, 0.30), "nonlinear-aero": (1e-5, 0.29),
                  "lon-lat-coupling": (0.2, 0.40), "attitude": (1e-4, 0.10)},
             ("flap-coupling",): {"nonlinear-aero": (1e-4, 0.05), "lon-lat-coupling": (0.5, 0.0),
                                  "attitude": (0.3, 0.01)},
             ("flap-coupling", "nonlinear-aero"): {"lon-lat-coupling": (0.5, 0.0),
                                                   "attitude": (0.4, 0.0)}}

    def fake(engine, halves, models, effect):
        p, g = table[tuple(e.name for e, _ in models[0])][effect.name]
        return types.SimpleNamespace(p=p, gain=g, mean=-math.log(1 - g), variants=(None,))

    monkeypatch.setattr(_selection, "evidence", fake)
    cands = [get_effect("flap-coupling"), get_effect("nonlinear-aero"),
             get_effect("lon-lat-coupling"), PROBES[0]]
    sel = _selection.forward_select(None, [None], cands)
    assert [e.name for e, _ in sel.chosen] == ["flap-coupling", "nonlinear-aero"]
    assert [added for _, _, added in sel.rounds] == ["flap-coupling", "nonlinear-aero", None]
