"""The choice of a selection round: the largest held-out gain that passes, whatever the
family (every family's size is chosen inside the fitting flights, so none is held back)."""

import types

from fwid.diagnosis._catalogue import CATALOGUE, get_effect
from fwid.diagnosis._probes import PROBES
from fwid.diagnosis import _selection


def test_probes_are_marked_and_no_entry_has_a_rule_of_its_own():
    assert all(p.probe for p in PROBES) and not any(e.probe for e in CATALOGUE)
    assert not any(hasattr(_selection, k) for k in ("RATES_MARGIN", "RATES_MIN_GAIN"))


def test_unsteady_aero_is_chosen_on_its_gain_and_may_follow_another_effect(monkeypatch):
    """No rates-first rule: `unsteady-aero` enters second when it passes after another."""
    import math

    table = {(): {"unsteady-aero": (1e-6, 0.10), "actuator-dynamics": (1e-6, 0.20)},
             ("actuator-dynamics",): {"unsteady-aero": (1e-5, 0.05)},
             ("actuator-dynamics", "unsteady-aero"): {}}

    def fake(engine, halves, models, effect):
        p, g = table[tuple(e.name for e, _ in models[0])][effect.name]
        return types.SimpleNamespace(p=p, gain=g, mean=-math.log(1 - g), variants=(None,))

    monkeypatch.setattr(_selection, "evidence", fake)
    sel = _selection.forward_select(None, [None], [get_effect("unsteady-aero"),
                                                   get_effect("actuator-dynamics")])
    assert [e.name for e, _ in sel.chosen] == ["actuator-dynamics", "unsteady-aero"]


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
