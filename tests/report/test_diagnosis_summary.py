"""The diagnosis summary in words, on flights that start in their manoeuvre."""

import math

import pytest

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


def _blocks_of(n: int, dt: float):
    """Stand-in test-flight signals for `heldout_test`: `n` samples at `dt`, blocked as the
    diagnosis blocks them (`Signals.block_rows`)."""
    import functools
    import types

    from fwid.diagnosis._signals import Signals

    s = types.SimpleNamespace(n=n, dt=dt)
    s.block_rows = functools.partial(Signals.block_rows, s)
    return s


def _heldout(shrink: float, flights: int, seed: int = 0):
    """`heldout_test` on `flights` test flights of 10 s whose error on Z shrinks by about
    `shrink` (a share), block to block by 0.9-1.1 times that."""
    import numpy as np

    from fwid.diagnosis._heldout import heldout_test

    rng = np.random.default_rng(seed)
    before, after, sigs = [], [], []
    for _ in range(flights):
        e = rng.normal(size=1000)
        per_block = np.repeat(1.0 - shrink * rng.uniform(0.9, 1.1, 10), 100)
        before.append({"Z": e})
        after.append({"Z": e * per_block + 0.05 * rng.normal(size=1000)})
        sigs.append(_blocks_of(1000, 0.01))
    rms = lambda xs: float(np.sqrt(np.mean(np.concatenate(xs) ** 2)))  # noqa: E731
    b, a = rms([x["Z"] for x in before]), rms([x["Z"] for x in after])
    observed = 100.0 * (1.0 - a / b)
    return observed, heldout_test(before, after, sigs, ["Z"], {"Z": b}, observed, 0.05,
                                  [f"f{k}" for k in range(flights)])


def test_a_shrink_inside_what_the_test_flights_resolve_is_within_their_noise():
    """The shrink's own test on the test flights' blocks: a shrink of about 0.3 % against
    noise of 5 % of the error per sample is within the noise, and more test flights would
    settle it (the smallest shrink resolved falls like 1 / sqrt(flights)); a 20 % shrink is
    not within it."""
    small, h = _heldout(0.003, 4)
    assert h["blocks"] == 40 and h["flights"] == ["f0", "f1", "f2", "f3"]
    assert h["within_noise"] and small < h["detection_limit_pct"]
    assert h["flights_to_settle"] > 4
    _, h16 = _heldout(0.003, 16, seed=1)
    assert 0.35 < h16["detection_limit_pct"] / h["detection_limit_pct"] < 0.65
    big, h = _heldout(0.2, 4)
    assert big > 15 and not h["within_noise"] and h["flights_to_settle"] is None
    assert h["p"] < 1e-6


def test_the_summary_says_which_flights_selected_and_scored_and_the_noise(tmp_path):
    """The summary says that the selection is a cross-fit over every flight, the test flights
    among them (true: its blocks are those of all six flights, and with training and test
    swapped its first round's p values stay close), that the shrink is scored on the test
    flights with the model fitted on the training ones, with its own p value there; and a
    verdict whose overall shrink is inside what those flights resolve says it is within their
    noise and how many would settle it."""
    import dataclasses

    for folder, seed in (("train", 3), ("test", 4)):
        write_flights(tmp_path / folder, 3, "lon", seed=seed, effect="actuator-dynamics")
    a, b = fwid.load_flights(tmp_path / "train"), fwid.load_flights(tmp_path / "test")
    d = fwid.diagnose(a, b, simulation=False)
    swapped = fwid.diagnose(b, a, simulation=False)
    assert all(r["blocks"] == len(d.folds) for r in d.rounds[0]["candidates"].values())
    assert len(d.folds) == len(swapped.folds) == 6 * 4
    for k, row in d.first_round.items():
        assert (row["p"] < 1e-3) == (swapped.first_round[k]["p"] < 1e-3), k
    text = diagnosis_summary(d)
    assert "cross-fit over all 6 flights" in text and "not unseen by it" in text
    assert "re-fitted on the 3 training flights only" in text
    c = d.candidate(d.verdict)
    h = c["heldout"]
    assert h["flights"] == [f.name for f in b] and h["blocks"] < len(d.folds) / 1.5
    assert f"on the test flights alone p = {h['p']:.2g} over their {h['blocks']} blocks" in text
    assert ("within the noise of these flights" in text) == h["within_noise"]
    # the same verdict with an overall shrink inside what its test flights resolve
    _, noisy = _heldout(0.003, 3)
    rows = [dict(r, heldout=noisy) if r["effect"] == d.verdict else r for r in d.candidates]
    text = diagnosis_summary(dataclasses.replace(d, candidates=rows))
    assert "within the noise of these flights (the smallest overall shrink their blocks " \
           f"resolve is {noisy['detection_limit_pct']:.1f} %)" in text
    assert f"about {noisy['flights_to_settle']} test flights like these would settle it" in text
