"""The discrimination score of benchmarks/design.py: ambiguous, decisive and right."""

import sys
from pathlib import Path
from types import SimpleNamespace

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from design import judge  # noqa: E402

NAMED = [{"effect": e} for e in ("actuator-dynamics", "unsteady-aero", "nonlinear-aero")]


def _diag(verdict, *sets):
    rows = [{"explanation": list(x), "p_value": 1.0 / (k + 1)} for k, x in enumerate(sets)]
    return SimpleNamespace(verdict=verdict, candidates=NAMED, confidence_set=rows)


def test_ambiguous_means_two_catalogue_leaders():
    j = judge(_diag("actuator-dynamics", ["actuator-dynamics"], ["unsteady-aero"]),
              "actuator-dynamics")
    assert j["ambiguous"] and j["right"] and not j["decisive_right"]
    assert j["rivals"] == ["actuator-dynamics", "unsteady-aero"]
    # a probe or none beside the truth: not ambiguous, yet not decisive either
    j = judge(_diag("actuator-dynamics", ["actuator-dynamics"], ["attitude"], []),
              "actuator-dynamics")
    assert not j["ambiguous"] and not j["decisive_right"]


def test_decisive_and_right_keeps_only_the_truths_explanations():
    j = judge(_diag("actuator-dynamics", ["actuator-dynamics"],
                    ["actuator-dynamics", "nonlinear-aero"]), "actuator-dynamics")
    assert j["decisive_right"] and not j["ambiguous"]
    j = judge(_diag("unsteady-aero", ["unsteady-aero", "actuator-dynamics"]),
              "actuator-dynamics")
    assert not j["decisive_right"] and not j["right"]
