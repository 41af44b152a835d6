"""The confidence set of explanations: the MCS p values, and the set a diagnosis reports."""

import math

import numpy as np
import pytest
from scipy import stats

import fwid
from types import SimpleNamespace

from fwid.diagnosis._confidence import (LEVEL, Explanation, better_p_value, confidence_set,
                                        mcs_p_values, parsimonious)
from fwid.report import diagnosis_summary


def test_a_clearly_worse_model_is_eliminated_and_the_best_keeps_p_one():
    rng = np.random.default_rng(0)
    base = rng.normal(size=(60, 1))
    losses = np.hstack([base, base + 1.0 + 0.1 * rng.normal(size=(60, 1)),
                        base + 2.0 + 0.1 * rng.normal(size=(60, 1))])
    p = mcs_p_values(losses, resamples=500)
    assert p[0] == 1.0 and p[1] < 0.01 and p[2] < 0.01
    assert p[2] <= p[1]  # the worst goes first; p values never fall along the eliminations


def test_two_models_p_value_is_the_two_sided_test_of_their_mean_difference():
    """With two models T_max is |mean difference| over its bootstrap standard error: the
    worse one's p value is close to the two-sided normal test's."""
    rng = np.random.default_rng(1)
    n = 400
    a = rng.normal(size=n)
    b = a + 0.12 + rng.normal(size=n)
    p = mcs_p_values(np.stack([a, b], axis=1), resamples=4000)
    diff = b - a
    z = diff.mean() / (diff.std(ddof=1) / math.sqrt(n))
    assert p[0] == 1.0
    assert p[1] == pytest.approx(2 * stats.norm.sf(abs(z)), abs=0.03)


def test_equally_good_models_stay_together():
    rng = np.random.default_rng(2)
    common = rng.normal(size=(80, 1))
    losses = common + 0.3 * rng.normal(size=(80, 3))
    losses[:, 2] += 5.0
    p = mcs_p_values(losses, resamples=1000)
    assert p[0] >= LEVEL and p[1] >= LEVEL and p[2] < 0.01


def test_the_one_sided_p_value_is_the_normal_test_of_the_mean_difference():
    rng = np.random.default_rng(3)
    n = 300
    smaller = rng.normal(size=n)
    larger = smaller - 0.1 + rng.normal(size=n)  # a little better
    d = larger - smaller
    z = d.mean() / (d.std(ddof=1) / math.sqrt(n))
    assert better_p_value(larger, smaller, resamples=4000) == pytest.approx(
        stats.norm.cdf(z), abs=0.03)
    assert better_p_value(smaller - 1.0, smaller) < 0.001  # clearly better
    assert better_p_value(smaller + 1.0, smaller) > 0.999  # clearly worse


def _explanation(names, loss):
    return Explanation(tuple(SimpleNamespace(name=n) for n in names), loss)


def test_a_larger_explanation_stays_only_when_it_is_significantly_better():
    """`A + B` holds `A`: dropped when `B` adds nothing beyond the noise (although the MCS,
    which cannot reject either, keeps both), kept when it is clearly better; an explanation
    that holds no kept one (`C`) is never dropped."""
    rng = np.random.default_rng(4)
    base = rng.normal(size=80)
    a = _explanation(["A"], base - 0.5)
    ab_noise = _explanation(["A", "B"], base - 0.5 + 0.05 * rng.normal(size=80))
    ab_real = _explanation(["A", "B"], base - 1.0 + 0.05 * rng.normal(size=80))
    c = _explanation(["C"], base - 0.5 + 0.05 * rng.normal(size=80))
    assert [x.names for x in parsimonious([ab_noise, a, c])] == [["A"], ["C"]]
    assert [x.names for x in parsimonious([ab_real, a, c])] == [["A", "B"], ["A"], ["C"]]
    # none is held by every explanation: one that is not significantly better goes
    none = _explanation([], base)
    e = 0.05 * rng.normal(size=80)
    charge = _explanation(["A"], base).charge  # the gain an effect must earn
    weak = _explanation(["A"], base + e - e.mean() - charge - 0.001)  # a fraction of its noise
    kept = confidence_set([none, weak], resamples=1000)
    assert weak.p_value >= LEVEL and [x.names for x in kept] == [[]]


def test_the_set_of_a_diagnosis(effect_flights):
    """A strong effect: the set holds it, never `none`; the single effect's held-out gain is
    the selection's own first-round gain (two computations of one number); the summary line
    appears only for a set of two or more."""
    train, test = (fwid.load_flights(p) for p in effect_flights("actuator-dynamics", seed=5))
    d = fwid.diagnose(train, test, simulation=False)
    rows = d.to_json()["confidence_set"]
    assert rows and all(r["explanation"] for r in rows)  # `none` is rejected
    assert rows[0]["explanation"][0] == d.verdict == "actuator-dynamics"
    assert all(r["p_value"] >= LEVEL for r in rows)
    single = [r for r in rows if r["explanation"] == ["actuator-dynamics"]]
    if single:
        assert single[0]["gain_pct"] == pytest.approx(
            d.first_round["actuator-dynamics"]["gain_pct"], rel=1e-9)
    charged = [r["loss"] + r["charge"] for r in rows]
    assert charged == sorted(charged)
    text = diagnosis_summary(d)
    assert ("cannot tell them apart" in text) == (len(rows) > 1)
    d.confidence_set = [dict(rows[0], explanation=["actuator-dynamics"]),
                        dict(rows[0], explanation=["time-offset", "attitude"], p_value=0.3)]
    assert ("actuator-dynamics, or time-offset + attitude: these flights cannot tell them "
            "apart") in diagnosis_summary(d)
    # two catalogue effects lead: the next flight is the one that tells them apart
    assert d.to_json()["next_flight"]["tell_apart"] == ["actuator-dynamics", "time-offset"]
    assert "fwid design --discriminate" in diagnosis_summary(d)
    d.confidence_set = [dict(rows[0], explanation=["actuator-dynamics"]),
                        dict(rows[0], explanation=["actuator-dynamics", "attitude"]),
                        dict(rows[0], explanation=["attitude"])]  # a probe: no catalogue rival
    assert d.next_flight is None and "--discriminate" not in diagnosis_summary(d)


def test_clean_flights_leave_none_alone(effect_flights):
    train, test = (fwid.load_flights(p) for p in effect_flights("none", seed=0))
    d = fwid.diagnose(train, test, simulation=False)
    assert d.verdict == "none"
    assert [r["explanation"] for r in d.confidence_set][0] == []


def _with_square(src, dst, load, state, frac):
    """Copy a folder of flights, adding to `load` a single quadratic term in `state` of
    `frac` times the load's spread."""
    dst.mkdir(parents=True, exist_ok=True)
    (dst / "vehicle.json").write_text((src / "vehicle.json").read_text())
    for csv in sorted(src.glob("*.csv")):
        header = csv.read_text().splitlines()[0]
        names = header.split(",")
        data = np.loadtxt(csv, delimiter=",", skiprows=1)
        x = data[:, names.index(state)] - data[0, names.index(state)]
        y = data[:, names.index(load)]
        data[:, names.index(load)] += frac * np.std(y) * x * x / np.std(x * x)
        np.savetxt(dst / csv.name, data, delimiter=",", header=header, comments="", fmt="%.12g")
    return dst


def test_nonlinear_aero_keeps_the_single_smooth_term(effect_flights, tmp_path):
    """A load with one quadratic term (`M += c w^2`): the family's size, chosen by
    leave-one-flight-out error, is a small member that holds `w`, not every state's finest
    shapes; the EOM of the simulation block gets a member's columns only."""
    from fwid.diagnosis._augment import augment

    train, test = effect_flights("none", seed=2, n_train=4, n_test=4)
    d = fwid.diagnose(fwid.load_flights(_with_square(train, tmp_path / "tr", "M", "w", 0.03)),
                      fwid.load_flights(_with_square(test, tmp_path / "te", "M", "w", 0.03)),
                      simulation=False)
    assert d.verdict == "nonlinear-aero"
    variant = d.effects[0]["variant"]
    from fwid.diagnosis._catalogue.nonlinear_aero import TERMS

    # a member that holds w, smaller than the whole family (the member the leave-one-flight-
    # out error picks among those that hold w^2: w's bend, or the products u w, w q, u q)
    assert variant is not None and "w" in variant and variant != TERMS[0].text("lon"), variant
    from fwid.diagnosis._catalogue._smooth import smooth_basis
    from fwid.diagnosis._catalogue.nonlinear_aero import Terms

    member = Terms((1,), 2, bases={"w": smooth_basis(np.linspace(-1.0, 1.0, 400))})
    model, _, _ = augment("lon", [("nonlinear-aero", member)])
    assert model.inputs == ("de",)  # in the simulated w: no prepared input
    new = set(model.free) - set(fwid.longitudinal().free)
    assert new == {"X_w1", "X_w2", "Z_w1", "Z_w2", "M_w1", "M_w2"}


class _Engine:
    """A stub of the attribution's engine: each effect lowers every block's error by its own
    factor (`FACTOR`), whatever it is paired with."""

    FACTOR = {"attitude": 0.7, "nonlinear-aero": 0.9, "actuator": 0.95, "unsteady-aero": 0.8}

    def channels(self, band):
        return [("M", band)]

    def block_errors(self, fit, score, model, band):
        f = np.prod([self.FACTOR[e.name] for e, _ in model]) if band == "averaged" else 1.0
        return np.full((len(score), 1), f) * (1.0 + 0.01 * np.arange(len(score)))[:, None]

    def choose(self, idx, model, e, sigma2):
        return None


def _stub_explanations(chosen):
    from fwid.diagnosis._confidence import explanations
    from fwid.diagnosis._significance import Half

    def effect(name, probe=False):
        return SimpleNamespace(name=name, band="averaged", probe=probe)

    by = {"attitude": effect("attitude", probe=True), "nonlinear-aero": effect("nonlinear-aero"),
          "actuator": effect("actuator"), "unsteady-aero": effect("unsteady-aero")}
    halves = [Half((0,), (1, 2, 3), {("M", "averaged"): 1.0, ("M", "flapping"): 1.0})]
    first = {n: SimpleNamespace(variants=(None,), mean=-np.log(f))
             for n, f in _Engine.FACTOR.items()}
    return [x.names for x in explanations(_Engine(), halves, first, list(by.values()),
                                          chosen=[by[n] for n in chosen])]


def test_an_entry_after_a_probe_is_no_explanation():
    """The forward selection chose a probe, then a catalogue entry: that entry only echoes the
    probe (`unexplained` reports it so), so the set's explanations hold the probe alone; an
    entry before a probe stays with it."""
    found = _stub_explanations(["attitude", "nonlinear-aero"])
    assert [x for x in found if "attitude" in x] == [["attitude"]]
    found = _stub_explanations(["nonlinear-aero", "actuator", "attitude"])
    assert ["nonlinear-aero", "actuator", "attitude"] in found


def test_unsteady_aero_pairs_like_any_entry():
    """`unsteady-aero` (one filtered quasi-steady column per load) pairs with the others."""
    found = _stub_explanations(["unsteady-aero", "nonlinear-aero"])
    assert ["unsteady-aero", "nonlinear-aero"] in found or \
        ["nonlinear-aero", "unsteady-aero"] in found
