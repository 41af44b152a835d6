"""`fwid.diagnose` on flights with a withheld effect: the verdict, the shrink, the gap map."""

import json
import random

import numpy as np
import pytest

import fwid
from fwid.diagnosis import BAND_NAMES, EFFECT_NAMES

from .conftest import resample


def _diagnose(train_dir, test_dir, axis="lon", shuffle=None):
    train = fwid.load_flights(train_dir)
    test = fwid.load_flights(test_dir)
    if shuffle is not None:
        random.Random(shuffle).shuffle(train)
        random.Random(shuffle + 1).shuffle(test)
    return fwid.diagnose(train, test, axis=axis, simulation=False)


#: The form each effect is withheld in: its default, except `unsteady-aero`'s, whose default
#: (`state-lag`) also lags every load on its own state, which no entry may fit (Section III:
#: the load is reconstructed from that state's rate); its Wagner-like lag of the lift on the
#: incidence is the family's own (the default is checked apart, below).
FORMS = {"unsteady-aero": "incidence-lag"}


@pytest.mark.parametrize("effect", EFFECT_NAMES)
def test_names_the_withheld_effect_and_the_error_shrinks(effect_flights, effect):
    d = _diagnose(*effect_flights(effect, strength=1.0, seed=1, form=FORMS.get(effect)))
    assert d.verdict == effect, [(c["effect"], c["significant"]) for c in d.candidates]
    top = d.candidates[0]
    assert top["effect"] == effect and top["significant"]
    assert top["shrink_pct"] > 0
    for ld in top["affected"]:
        assert top["test_rms_after"][ld] < top["test_rms_before"][ld]
        band = top["test_rms_in_band"][ld]
        assert band["after"] < 0.9 * band["before"]  # in its own band the gap closes clearly
    assert [e["effect"] for e in d.effects] == [effect]  # nothing else is added


def test_the_default_lag_of_every_state_is_kept(effect_flights):
    """`unsteady-aero`'s default form lags every state, a load's own too: the family holds
    the part the flights can show, and the confidence set keeps it."""
    d = _diagnose(*effect_flights("unsteady-aero", strength=1.0, seed=1))
    assert ["unsteady-aero"] in [x["explanation"] for x in d.confidence_set]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_none_on_clean_flights(effect_flights, seed):
    d = _diagnose(*effect_flights("none", seed=seed))
    assert d.verdict == "none" and d.unexplained is None
    assert d.process_noise is None and d.to_json()["process_noise"] is None  # no filter error
    assert not any(c["significant"] for c in d.candidates + d.probes)
    assert d.disturbance["redness"] < d.disturbance["red_min"]  # what is left is noise


@pytest.mark.parametrize("effect", ["none", "lon-lat-coupling", "actuator-dynamics"])
def test_lateral_axis(effect_flights, effect):
    d = _diagnose(*effect_flights(effect, axis="lat", seed=4), axis="lat")
    assert d.verdict == effect


def test_verdict_stable_under_shuffle_resample_and_cut(effect_flights, tmp_path):
    train, test = effect_flights("actuator-dynamics", seed=5)
    ref = _diagnose(train, test)
    assert ref.verdict == "actuator-dynamics"
    shuffled = _diagnose(train, test, shuffle=7)
    assert shuffled.verdict == ref.verdict
    assert [c["effect"] for c in shuffled.candidates] == [c["effect"] for c in ref.candidates]
    np.testing.assert_allclose(shuffled.candidates[0]["shrink_pct"],
                               ref.candidates[0]["shrink_pct"], rtol=1e-9)
    for rate, cut in ((100.0, 0.0), (250.0, 0.0), (200.0, 0.3)):
        d = _diagnose(resample(train, tmp_path / f"tr{rate}{cut}", rate, cut),
                      resample(test, tmp_path / f"te{rate}{cut}", rate, cut))
        assert d.verdict == ref.verdict, (rate, cut)


@pytest.mark.parametrize("effect", EFFECT_NAMES)
def test_four_plus_four_flights_suffice(effect_flights, effect):
    """A campaign of 4 training and 4 test flights: each effect at strength 1 is named, with
    a small p value, and nothing else is added."""
    d = _diagnose(*effect_flights(effect, strength=1.0, seed=6, n_train=4, n_test=4,
                                  form=FORMS.get(effect)))
    assert d.verdict == effect, [(c["effect"], c["p"]) for c in d.candidates]
    assert [e["effect"] for e in d.effects] == [effect]
    top = d.candidate(effect)
    assert top["p"] < 0.01 / len(EFFECT_NAMES) and top["confidence"] > 0.99
    assert len(d.folds) >= 8 * 4  # 4.5 s flights: four or more blocks each
    assert top["detection_limit_pct"] < top["evidence"]["heldout_gain_pct"] + 10


def test_block_statistic_is_a_one_sided_t_test(effect_flights):
    """The p value is the one-sided one-sample t test of the per-block log ratios, computed
    here by scipy from the engine's block errors (an independent re-assembly)."""
    from scipy import stats

    from fwid.diagnosis._attribution import Engine, units
    from fwid.diagnosis._significance import scoring_blocks
    from fwid.diagnosis._significance import Half, evidence
    from fwid.diagnosis._signals import signals

    train, test = (fwid.load_flights(p) for p in effect_flights(
        "actuator-dynamics", strength=1.0, seed=6, n_train=4, n_test=4))
    tr, te = [signals(f) for f in train], [signals(f) for f in test]
    trb, trp = scoring_blocks(tr, 0)
    teb, tep = scoring_blocks(te, 4)
    eng = Engine(units(tr + te) + units(trb + teb, trp + tep), ("X", "Z", "M"))
    a, b = (0, 1, 2, 3), (4, 5, 6, 7)
    nb = len(trb)
    halves = [Half(a, tuple(range(8 + nb, 8 + nb + len(teb))), eng.mean_square(a)),
              Half(b, tuple(range(8, 8 + nb)), eng.mean_square(b))]
    act = [e for e in eng.catalogue if e.name == "actuator-dynamics"][0]
    ev = evidence(eng, halves, [(), ()], act)
    d = []
    for h, v in zip(halves, ev.variants):
        w = np.array([1 / h.sigma2[(ld, "averaged")] for ld in ("X", "Z", "M")])
        for i in h.score:
            e0 = e1 = 0.0
            for ld, wl in zip(("X", "Z", "M"), w):
                ch = (ld, "averaged")
                th0 = eng.fit(h.fit, ch)[0]
                th1 = eng.fit(h.fit, ch, ((act, v),))[0]
                e0 += wl * np.sum(eng.residual(i, ch, th0) ** 2)
                e1 += wl * np.sum(eng.residual(i, ch, th1, ((act, v),)) ** 2)
            d.append(np.log(e0 / e1))
    ref = stats.ttest_1samp(d, 0.0, alternative="greater")
    assert ev.p == pytest.approx(ref.pvalue, rel=1e-9)
    assert ev.t == pytest.approx(ref.statistic, rel=1e-9)
    # block regressors are the flight's, sliced: the lag starts at the flight's first sample
    blk = eng.units[8 + 1]
    np.testing.assert_array_equal(eng.design(8 + 1, ("M", "averaged"), ((act, v),)),
                                  eng.design(blk.parent, ("M", "averaged"), ((act, v),))[blk.rows])


def test_report_follows_the_contract(effect_flights):
    d = _diagnose(*effect_flights("flap-coupling", seed=1))
    rep = json.loads(json.dumps(d.to_json()))
    assert rep["verdict"] == "flap-coupling"
    assert rep["effects"][0]["effect"] == "flap-coupling"
    for k, e in enumerate(rep["effects"]):
        # the loads it acts on (leave-one-flight-out), and how sure a further effect is
        assert set(e["acts_on"]) <= set(rep["method"]["loads"]) and e["acts_on"]
    assert rep["effects"][0]["relative_gain"] == pytest.approx(1.0)
    # the confidence set: the verdict's explanation first, p values at or above its level
    kept = rep["confidence_set"]
    assert kept[0]["explanation"][0] == rep["verdict"]
    assert all(x["p_value"] >= rep["method"]["confidence_level"] for x in kept)
    for c in rep["candidates"]:
        assert {"effect", "significant", "shrink_pct", "test_rms_before",
                "test_rms_after", "p", "confidence", "detection_limit_pct"} <= set(c)
        assert 0.0 <= c["p"] <= 1.0 and 0.0 <= c["confidence"] <= 1.0
        assert c["effect"] in EFFECT_NAMES
    # the selection's trace: what each round added, at alpha / candidates in play, and why
    rounds = rep["rounds"]
    added = [r["added"] for r in rounds if r["added"] is not None]
    assert added[0] == "flap-coupling"
    assert [e["effect"] for e in rep["effects"]] == [a for a in added if a in EFFECT_NAMES]
    for r in rounds:
        assert r["level"] == pytest.approx(rep["method"]["alpha"] / len(r["candidates"]))
        for name, c in r["candidates"].items():
            assert (name == r["added"]) <= (c["p"] < r["level"]), (name, c)
    assert rounds[0]["candidates"]["flap-coupling"]["p"] == pytest.approx(
        rep["first_round"]["flap-coupling"]["p"])
    # the detection limit: these flights, the first round's level, its flight-count rule
    det = rep["detection"]
    assert det["flights"] == len(rep["train"]) + len(rep["test"]) and det["power"] == 0.8
    assert det["level"] == pytest.approx(rounds[0]["level"])
    assert det["blocks"] == len(d.folds)
    assert det["min_gain_pct"] < det["limit_pct"] < 100.0
    assert det["flights_for"]["1"] is None and det["flights_for"]["2"] is None
    m5 = det["flights_for"]["5"]
    assert (m5 <= det["flights"]) == (det["limit_pct"] <= 5.0)
    loc = rep["localisation"]
    assert {"by_output", "by_band", "by_time", "by_state"} <= set(loc)
    for ld, bands in loc["by_band"].items():
        assert set(bands) == set(BAND_NAMES)
        assert sum(bands.values()) == pytest.approx(100.0)
    assert sum(v["share_pct"] for v in loc["by_output"].values()) == pytest.approx(100.0)
    # the shares are the axis's: a quiet other axis's loads (noise) do not crowd them out
    assert sum(loc["by_output"][ld]["share_pct"] for ld in ("X", "Z", "M")) == pytest.approx(100.0)
    for ld in set(loc["by_output"]) - {"X", "Z", "M"}:
        assert loc["by_output"][ld]["share_pct"] == 0.0 and loc["by_output"][ld]["other_axis"]
    # flapping modulated by the motion: its gap lives in the sidebands of the harmonics
    for ld in ("X", "Z", "M"):
        side = sum(loc["by_band"][ld][f"sidebands_{n}"] for n in (1, 2, 3))
        assert side > loc["by_band"][ld]["averaged"]
        assert loc["by_time"][ld]["manoeuvre_to_steady"] > 1.0


def test_bad_input_names_what_and_where(effect_flights, tmp_path):
    train, test = effect_flights("none", seed=0)
    flights = fwid.load_flights(train)
    with pytest.raises(fwid.InputError, match=r"lon_1\.csv: missing column 'M'"):
        fwid.diagnose([f.with_columns() for f in flights[:1]] +
                      [_drop(flights[1], "M")], fwid.load_flights(test))
    still = [f.with_columns(de=f["de"] * 0 + f.trim_value("de")) for f in flights]
    with pytest.raises(fwid.ExcitationError, match="excitation"):
        fwid.diagnose(still, fwid.load_flights(test))
    with pytest.raises(fwid.InputError, match="axis"):
        fwid.diagnose(flights, flights, axis="yaw")


def _drop(flight, col):
    import equinox as eqx

    cols = {k: v for k, v in flight.columns.items() if k != col}
    return eqx.tree_at(lambda f: f.columns, flight, cols)


def test_summary_and_gap_map_talk_about_the_axis(effect_flights):
    """The terminal quotes the in-band shrink as the headline next to the overall one; the
    gap map shows the axis's own loads only."""
    from fwid.report import diagnosis_summary, plot_gap_map
    from fwid.report._diagnosis import _band_label, in_band_shrink

    d = _diagnose(*effect_flights("flap-coupling", seed=1))
    c = d.candidate(d.verdict)
    band = in_band_shrink(c)
    pairs = [(c["test_rms_in_band"][ld]["before"], c["test_rms_in_band"][ld]["after"])
             for ld in c["affected"]]
    assert band == pytest.approx(100 * (1 - np.sqrt(np.mean([(a / b) ** 2 for b, a in pairs]))))
    text = diagnosis_summary(d)
    label = _band_label(c["band"])
    assert (f"{band:.1f} % in its band ({label}), {c['shrink_pct']:.1f} % over all "
            "frequencies" in text)
    # the table's columns said in words, each p the candidate's test alone (first round)
    assert "(chosen: kept by the forward selection" in text
    for c in d.candidates:
        row = next(r for r in text.splitlines() if r.strip().startswith(c["effect"] + " "))
        assert f"{d.first_round[c['effect']]['p']:8.2g}" in row, row
    # the gap in the figure's words, no internal band names
    assert "where the model misses" in text and "band averaged" not in text
    # a set of more than one explanation is said
    assert ("cannot tell them apart" in text) == (len(d.confidence_set) > 1)
    fig = plot_gap_map(d)
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert [lab.split()[0] for lab in labels] == ["X", "Z", "M"]
    # the gap grows with a state of the manoeuvred axis, never one of the quiet axis
    tops = {st["top"] for st in d.localisation["by_state"].values()}
    assert tops <= {"u", "w", "q", "de"}, tops
    # a catalogue effect chosen after a probe is in the table as chosen: the summary says
    # why it is not the verdict
    then = dict(d.effects[0])
    d.effects, d.verdict = [], "unexplained"
    d.unexplained = {"probe": "attitude", "description": "loads follow the attitude angle",
                     "drivers": [{"signal": "theta", "share_pct": 100.0}], "p": 1e-6,
                     "variant": None, "affected": ["M"], "test_shrink_pct": 3.0,
                     "redness_after": 0.5, "then": [then]}
    assert (f"then, after the attitude probe: {then['effect']}" in diagnosis_summary(d)
            and "not named: selected after structure outside the catalogue" in
            diagnosis_summary(d))


def test_warns_when_the_flights_manoeuvre_in_the_other_axis(effect_flights):
    """Lateral manoeuvres diagnosed on the default (lon) axis: a warning names the axis to
    pass; the diagnosis still runs."""
    train, test = (fwid.load_flights(p) for p in effect_flights("none", axis="lat", seed=5,
                                                                 n_train=4, n_test=4))
    with pytest.warns(fwid.DiagnosisWarning, match="axis='lat'"):
        d = fwid.diagnose(train, test, simulation=False)
    assert d.axis == "lon"
