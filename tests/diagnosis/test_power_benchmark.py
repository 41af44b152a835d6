"""A fast slice of `benchmarks/diagnosis_power.py`: its split cannot leak, its cases run blind
through `fwid diagnose`, and its summary counts them."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import diagnosis_power as dp  # noqa: E402
from _power_summary import (  # noqa: E402
    catalogue_pairs,
    peer_table,
    set_score,
    set_table,
    summarise,
)


def test_halves_share_no_form_and_no_seed():
    dev, held = dp.cases("dev"), dp.cases("heldout")
    for kind in ("single", "pair"):
        forms = [{(c["effect"], c["form"]) for c in cs if c["kind"] == kind} for cs in (dev, held)]
        assert forms[0] and forms[1] and not forms[0] & forms[1]
    assert not {c["seed"] for c in dev} & {c["seed"] for c in held}
    # more seeds add cases and keep the first ones as they were
    more = dp.cases("heldout", seeds=3)
    assert len(more) > len(held) and all(c in more for c in held)


def test_held_out_only_forms_never_reach_the_development_half():
    """Every catalogue family has a form the development half never shows, alone or in a
    pair; the held-out half shows each of them."""
    from fwid.synth import EFFECTS, FORMS

    assert set(dp.HELDOUT_ONLY) == set(EFFECTS[1:])
    only = {(e, f) for e, fs in dp.HELDOUT_ONLY.items() for f in fs}
    assert all(f in FORMS[e] for e, f in only)

    def shown(cs):
        return {(e, f) for c in cs for e, f in zip(c["effect"].split("+"), c["form"].split("+"))}

    assert not shown(dp.cases("dev")) & only
    held = dp.cases("heldout")
    assert only <= shown([c for c in held if c["kind"] == "single"])


def test_slice_runs_blind_and_is_summarised(tmp_path):
    cases = dp.cases("dev")
    pick = [next(c for c in cases if c["kind"] == "single" and c["n"] == 4
                 and c["effect"] == "lon-lat-coupling" and c["strength"] == 2.0
                 and c["form"] == "control" and c["seed"] == 2),
            next(c for c in cases if c["kind"] == "clean" and c["n"] == 4 and c["seed"] == 2
                 and c["rep"] == 0)]
    recs = [dp.run_case(dict(c)) for c in pick]
    assert [r.get("verdict") for r in recs] == ["lon-lat-coupling", "none"], recs
    hit = recs[0]
    assert hit["effects"][0] == "lon-lat-coupling"
    trace = hit["rounds"]
    assert trace[0]["added"] == "lon-lat-coupling" and trace[-1]["added"] is None
    assert trace[0]["candidates"]["lon-lat-coupling"]["p"] < trace[0]["level"]
    text = summarise(recs, tmp_path / "slice")
    assert "| lon-lat-coupling | 4+4 | 1/1 | 1/1 |" in text
    assert "| none | 4+4 | 0 | 1 | 1 | none 1 |" in text
    assert (tmp_path / "slice.png").stat().st_size > 0
    # the confidence sets are recorded and scored
    assert recs[0]["confidence_set"][0]["explanation"][0] == "lon-lat-coupling"
    assert recs[1]["confidence_set"][0]["explanation"] == []
    assert "## The confidence set of explanations" in text
    back = [json.loads(json.dumps(r)) for r in recs]  # the records are what the .jsonl holds
    assert [r["verdict"] for r in back] == ["lon-lat-coupling", "none"]
    # the SINDy peer ran on the same flights, its verdict recorded beside fwid's
    for r in back:
        assert set(r["sindy"]) >= {"verdict", "kept", "families", "wall_s"}, r["sindy"]
    assert "| SINDy (pysindy) |" in text
    assert "sindy" not in dp.run_case(dict(pick[1]), peer=False)


def test_the_set_is_scored_for_coverage_decisiveness_alarms_and_pairs():
    def rec(kind, effect, *kept, n=6, strength=1.0, verdict=None):
        return {"kind": kind, "effect": effect, "n": n, "strength": strength,
                "verdict": verdict or (kept[0][0] if kept[0] else "none"),
                "effects": [e for e in kept[0] if e != "attitude"],
                "confidence_set": [{"explanation": list(x), "p_value": 1.0} for x in kept]}

    alone = rec("single", "nonlinear-aero", ["nonlinear-aero", "attitude"])
    assert set_score(alone) == {"covered": True, "holds": True, "decisive": True,
                                "decisive_wrong": False, "alarm": False,
                                "best": "nonlinear-aero", "size": 1}  # a probe is no rival
    two = rec("single", "nonlinear-aero", ["unsteady-aero"], ["nonlinear-aero"])
    assert set_score(two)["covered"] and not set_score(two)["decisive"]
    assert set_score(two)["best"] == "unsteady-aero"
    missed = rec("single", "nonlinear-aero", ["nonlinear-aero", "time-offset"])
    assert not set_score(missed)["covered"]  # the truth alone is not an explanation kept
    assert set_score(missed)["holds"] and set_score(missed)["decisive_wrong"]
    wrong = rec("single", "nonlinear-aero", ["unsteady-aero", "attitude"], ["unsteady-aero"])
    assert set_score(wrong)["decisive_wrong"]  # every explanation names the same other entry
    assert not set_score(two)["decisive_wrong"]  # two rivals: not decisive either way
    nothing = rec("single", "nonlinear-aero", [])
    assert not set_score(nothing)["decisive_wrong"]  # none: the detection limit, no name
    clean = rec("clean", "none", [], ["attitude"])
    assert not set_score(clean)["alarm"] and set_score(clean)["best"] == "none"
    alarm = rec("out", "turbulence", ["attitude"], ["unsteady-aero"], verdict="unexplained")
    assert set_score(alarm)["alarm"] and set_score(alarm)["best"] == "unexplained"
    pair = rec("pair", "flap-coupling+time-offset", ["time-offset"],
               ["time-offset", "flap-coupling"])
    assert set_score(pair)["covered"]
    text = "\n".join(set_table([alone, two, missed, clean, alarm, pair]))
    assert "| single, strength 1, 6+6 | 3 | 2/3 | 3/3 | 1/3 | 2/3 | 2/3 | 1.3 |" in text
    assert "a kept explanation holds both effects in 1/1" in text
    assert "a catalogue name in the set of 1/2 clean and out-of-catalogue cases" in text
    assert set_score({"kind": "single", "effect": "x", "verdict": "x"}) is None


def test_the_summary_shows_the_peer_beside_fwid(tmp_path):
    """Given records with the peer's verdict, the summary has a SINDy row beside fwid's for the
    same targets: single effects at strength 1 (6+6 and 4+4), pairs, false alarms."""
    def rec(kind, effect, verdict, peer, kept=None, n=6, strength=1.0, effects=None):
        return {"kind": kind, "effect": effect, "form": "f", "strength": strength, "n": n,
                "seed": 1, "rep": 0, "axis": "lon", "verdict": verdict, "wall_s": 2.0,
                "effects": effects if effects is not None else
                ([] if verdict == "none" else [verdict]),
                "confidence_set": [{"explanation": effects or ([] if verdict == "none"
                                                               else [verdict]), "p_value": 1.0}],
                "sindy": {"verdict": peer, "kept": kept if kept is not None else
                          ([] if peer == "none" else [peer]), "families": {}, "wall_s": 0.5}}

    lines = [rec("single", "nonlinear-aero", "nonlinear-aero", "nonlinear-aero",
                 kept=["nonlinear-aero", "unsteady-aero"]),
             rec("single", "time-offset", "time-offset", "actuator-dynamics",
                 kept=["actuator-dynamics", "time-offset"]),
             rec("single", "flap-coupling", "flap-coupling", "none", n=4),
             rec("pair", "flap-coupling+time-offset", "time-offset", "time-offset",
                 kept=["time-offset", "flap-coupling"],
                 effects=["time-offset", "flap-coupling"]),
             rec("clean", "none", "none", "unsteady-aero"),
             rec("out", "cg-offset", "unexplained", "none")]
    path = tmp_path / "fake.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in lines))
    back = [json.loads(x) for x in path.read_text().splitlines()]
    text = "\n".join(peer_table(back))
    assert "| fwid | 2/2 | 2/2 | 2/2 | 1/1 | 1/1 | 0/2 | 2.0, 2.0 |" in text
    assert "| SINDy (pysindy) | 1/2 | 2/2 | 0/2 | 0/1 | 1/1 | 1/2 | 0.5, 0.5 |" in text
    assert "6 cases with both verdicts" in text
    md = summarise(back, tmp_path / "fake")
    assert "## A peer beside fwid (the same flights)" in md and "| SINDy (pysindy) |" in md
    old = [{k: v for k, v in r.items() if k != "sindy"} for r in back]  # --no-peer
    assert peer_table(old) == ["(no peer ran: `--no-peer`)"]


def test_pairs_are_also_scored_against_issue_12s_catalogue():
    """Pairs of the original four need both named; with `unsteady-aero` (outside the original
    catalogue) the other effect must be named; the extended pairs count both."""
    def rec(effect, effects):
        return {"kind": "pair", "effect": effect, "effects": effects, "verdict": effects[0]}

    rows = [rec("flap-coupling+nonlinear-aero", ["flap-coupling", "nonlinear-aero"]),
            rec("flap-coupling+actuator-dynamics", ["flap-coupling"]),
            rec("time-offset+flap-frequency", ["time-offset", "flap-frequency"]),
            rec("unsteady-aero+time-offset", ["time-offset"]),
            rec("actuator-dynamics+unsteady-aero", ["unsteady-aero"]),
            rec("unsteady-aero+lon-lat-coupling", ["lon-lat-coupling", "unsteady-aero"])]
    text = "\n".join(catalogue_pairs(rows))
    assert "the original four effects, both named: 1/2;" in text
    assert "without `unsteady-aero`, both named: 2/3;" in text
    assert "the other effect named: 2/3 (both: 1);" in text
    assert "all pairs so scored: 4/6." in text


def test_subset_groups_take_a_case_in_any_group():
    cases = [{"kind": "single", "strength": 1.0, "effect": "a"},
             {"kind": "single", "strength": 2.0, "effect": "a"},
             {"kind": "pair", "strength": 1.0, "effect": "a+b"},
             {"kind": "clean", "strength": 0.0, "effect": "none"}]
    got = dp.select(cases, ["kind=single", "strength=1.0", "|", "kind=clean"], None)
    assert got == [cases[0], cases[3]]
    assert dp.select(cases, ["effect=b"], None) == [cases[2]]


def test_weak_cases_get_fwids_flight_count_and_the_promise_is_counted():
    from _power_summary import truth_gain_table
    from fwid.diagnosis._detection import DetectionLimit

    det = DetectionLimit(sd=0.08, blocks=40, flights=8, train=4, test=4, level=0.05 / 12,
                         min_gain=0.02).as_dict()

    def rec(effect, gain, verdict, seed):
        r = {"kind": "single", "effect": effect, "form": "f", "strength": 1.0, "n": 4,
             "seed": seed, "verdict": verdict, "effects": [verdict],
             "first_round": {effect: {"gain_pct": gain, "p": 0.01, "t": 3.0}},
             "detection": det}
        dp.truth_gain(r)
        return r

    rows = [rec("nonlinear-aero", 9.0, "nonlinear-aero", 0),
            rec("unsteady-aero", 3.0, "none", 1), rec("time-offset", 1.5, "none", 2)]
    for r in rows:
        r["confidence_set"] = [{"explanation": [r["verdict"]] if r["verdict"] != "none"
                                else [], "p_value": 1.0}]
    pair = {"kind": "pair", "effect": "time-offset+flap-coupling", "verdict": "time-offset",
            "effects": ["time-offset", "flap-coupling"],
            "first_round": {"time-offset": {"gain_pct": 12.0}, "flap-coupling":
                            {"gain_pct": 3.5}, "nonlinear-aero": {"gain_pct": 1.0}},
            "confidence_set": [{"explanation": ["time-offset", "flap-coupling"],
                                "p_value": 1.0}]}
    dp.truth_gain(pair)
    assert pair["truth_gain_pct"] == 3.5  # the weaker of its two effects
    assert pair["truth_gains_pct"] == {"time-offset": 12.0, "flap-coupling": 3.5}
    assert rows[0]["truth_gain_pct"] == 9.0 and "flights_for_truth" not in rows[0]
    assert rows[1]["flights_for_truth"] == det["flights_for"]["3"] >= 8
    assert rows[2]["flights_for_truth"] is None  # below the 2 % that counts: never
    promised = [{"effect": "unsteady-aero", "form": "f", "strength": 1.0, "n": 4, "seed": 1,
                 "found": True, "verdict": "unsteady-aero"}]
    text = "\n".join(truth_gain_table(rows + [pair], promised))
    assert "| >= 4 % | 4+4 | 1 | 1/1 | 1/1 (100 %) | 1/1 (100 %) | 0/1 (0 %) |" in text
    assert "| < 4 % | 4+4 | 2 | 0/2 | 0/2 (0 %) | 0/2 (0 %) | 0/2 (0 %) |" in text
    assert "| < 4 % | 1 | 1/1 (100 %) | 1/1 |" in text  # the pair, by its weaker effect
    assert f"| unsteady-aero | f | 4+4 | 3.00 | {det['flights_for']['3']} | yes |" in text
    assert "| time-offset | f | 4+4 | 1.50 | never | - |" in text
    assert "The promise (named at fwid's flight count, target >= 80 %): 1/1 (100 %)" in text
