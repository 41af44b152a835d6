"""The folds of the cross-fit: every block scored once, by a model not fitted on its flight,
whatever order the flights come in; and a diagnosis with more folds still names the effect."""

from __future__ import annotations

import types

import fwid
from fwid.diagnosis._significance import cross_fit_folds, default_folds


class _Engine:
    def __init__(self, names):
        self.units = [types.SimpleNamespace(signals=types.SimpleNamespace(name=n, n=100))
                      for n in names]

    def mean_square(self, idx):
        return {"fit": idx}


def _folds(names, n_train, k, blocks_per_flight=3):
    n = len(names)
    parents = [f for f in range(n) for _ in range(blocks_per_flight)]
    eng = _Engine(names + [f"b{j}" for j in range(len(parents))])
    return cross_fit_folds(eng, n, parents, n_train, k), parents


def test_every_block_scored_once_by_a_model_not_fitted_on_its_flight():
    names = [f"lon_{i}.csv" for i in range(5)] * 2  # training and test share names
    for k in (2, 3, 8, 20):
        halves, parents = _folds(names, 5, k)
        assert len(halves) == min(k, 10)
        scored = sorted(j for h in halves for j in h.score)
        assert scored == list(range(10, 10 + len(parents)))
        for h in halves:
            assert not {parents[j - 10] for j in h.score} & set(h.fit)
            assert h.sigma2 == {"fit": h.fit}


def test_two_folds_are_training_and_test():
    assert default_folds(8) == 8 and default_folds(9) == 2
    halves, _ = _folds(["a", "b", "c", "d"], 2, 2)
    assert [h.fit for h in halves] == [(0, 1), (2, 3)]


def test_groups_do_not_depend_on_the_order_given():
    names = ["c", "a", "d", "b"]
    perm = [1, 3, 0, 2]  # the same flights, sorted
    halves, _ = _folds(names, 4, 3)
    again, _ = _folds([names[i] for i in perm], 4, 3)
    as_names = sorted(tuple(sorted(names[i] for i in h.fit)) for h in halves)
    again_names = sorted(tuple(sorted(names[perm[i]] for i in h.fit)) for h in again)
    assert as_names == again_names


def test_few_flights_get_eight_folds_and_two_can_be_asked_for(effect_flights):
    train, test = effect_flights("actuator-dynamics", strength=1.0, seed=6, n_train=4, n_test=4)
    tr, te = fwid.load_flights(train), fwid.load_flights(test)
    d = fwid.diagnose(tr, te, simulation=False, process_noise=False)
    assert d.verdict == "actuator-dynamics"
    assert "8 folds" in d.settings["significance"]
    two = fwid.diagnose(tr, te, simulation=False, process_noise=False, folds=2)
    assert two.verdict == "actuator-dynamics"
    assert "score test blocks" in two.settings["significance"]
