"""The detection limit of a diagnosis and its flight-count rule (`_detection.py`)."""

import math

import numpy as np
import pytest
from scipy import stats

from fwid.diagnosis._confidence import LEVEL as SET_LEVEL
from fwid.diagnosis._detection import DetectionLimit, detection_limit, flights_needed
from fwid.diagnosis._selection import passes
from fwid.diagnosis._significance import Evidence


def _limit(sd=0.05, blocks=80, flights=16, level=0.05 / 12, min_gain=0.02):
    return DetectionLimit(sd=sd, blocks=blocks, flights=flights, train=flights // 2,
                          test=flights - flights // 2, level=level, min_gain=min_gain)


def test_without_the_floor_it_is_the_candidates_limit_and_falls_like_one_over_sqrt_flights():
    rng = np.random.default_rng(0)
    d = rng.normal(0.01, 0.2, size=120)
    ev = Evidence("x", (), d, {}, {})
    lim = DetectionLimit(sd=float(np.std(d, ddof=1)), blocks=120, flights=12, train=6, test=6,
                         level=0.01, min_gain=0.0)
    assert lim.limit() == pytest.approx(ev.detection_limit(0.01))
    # in log units the limit is (t_level + t_power) se: 16 times the flights, a quarter of it
    # (up to the t quantiles' fall with the degrees of freedom)
    ratio = -math.log1p(-lim.limit(12 * 16)) / -math.log1p(-lim.limit(12))
    assert 0.23 < ratio < 0.25


def test_flights_needed_is_the_fewest_flights_whose_limit_reaches_the_gain():
    lim = _limit()
    for g in (2.1, 2.5, 3, 4, 5, 10, 30):
        m = lim.flights_needed(g)
        assert lim.limit(m) <= g / 100 < (lim.limit(m - 1) if m > 1 else 1.0)
    needs = [lim.flights_needed(g) for g in (2.2, 2.5, 3, 4, 5, 10)]
    assert needs == sorted(needs, reverse=True) and needs[0] > needs[-1]
    # consistent with the limit at these flights: a gain just above it needs at most them
    here = 100 * lim.limit()
    assert lim.flights_needed(here + 1e-6) <= lim.flights <= lim.flights_needed(here - 0.05)


def test_a_gain_at_or_below_the_smallest_that_counts_is_never_found():
    lim = _limit()
    assert lim.flights_needed(2.0) is None and lim.flights_needed(1.0) is None
    assert lim.limit(10**6) > 0.02  # the limit approaches the floor from above
    block = lim.as_dict()
    assert block["flights_for"]["1"] is None and block["flights_for"]["2"] is None
    assert block["flights_for"]["5"] == lim.flights_needed(5)
    assert flights_needed(block, 3.0) == lim.flights_needed(3.0)  # back from the JSON


def _named(d, lim):
    """Whether block scores `d` get the effect named: the selection's rule (`passes`: the t
    test at the level and the smallest gain) and the confidence set's test against `none`
    (the mean significantly above the charge at the set's level; its block bootstrap is the
    normal test of the mean, `test_confidence.py`)."""
    charge = -math.log1p(-lim.min_gain)
    t = (np.mean(d) - charge) / (np.std(d, ddof=1) / math.sqrt(d.size))
    return passes(Evidence("x", (), d, {}, {}), lim.level, lim.min_gain) and \
        t > stats.t.isf(SET_LEVEL, d.size - 1)


def test_a_gain_at_the_limit_is_found_with_eighty_percent_power():
    """Simulated block scores with the true mean at the limit get the effect named (the
    selection's rule and the set's test) about 80 % of the time."""
    lim = _limit(sd=0.08, blocks=60, flights=12)
    dtrue = -math.log1p(-lim.limit())
    rng = np.random.default_rng(1)
    found = [_named(rng.normal(dtrue, 0.08, size=60), lim) for _ in range(3000)]
    assert np.mean(found) == pytest.approx(0.8, abs=0.03)
    # at the flights it needs for a 4 % gain, a 4 % gain is found at least as often
    m = lim.flights_needed(4.0)
    n = round(lim.blocks_per_flight * m)
    found = [_named(rng.normal(-math.log(0.96), 0.08, size=n), lim) for _ in range(3000)]
    assert np.mean(found) >= 0.77


def test_the_spread_is_the_strongest_entrys_not_below_the_median():
    rng = np.random.default_rng(2)
    first = {n: Evidence(n, (), rng.normal(m, s, size=40), {}, {})
             for n, m, s in (("a", 0.0, 0.1), ("b", 0.0, 0.2), ("c", 0.0, 0.4),
                             ("strong", 0.3, 0.3), ("probe", 5.0, 5.0))}
    lim = detection_limit(first, ["a", "b", "c", "strong"], 0.01, 0.02, 3, 2)
    assert lim.sd == pytest.approx(float(np.std(first["strong"].d, ddof=1)))
    quiet = {**first, "strong": Evidence("strong", (), rng.normal(0.3, 0.01, size=40), {}, {})}
    lim = detection_limit(quiet, ["a", "b", "c", "strong"], 0.01, 0.02, 3, 2)
    spreads = [float(np.std(quiet[n].d, ddof=1)) for n in ("a", "b", "c", "strong")]
    assert lim.sd == pytest.approx(float(np.median(spreads)))
    assert (lim.flights, lim.train, lim.test, lim.blocks) == (5, 3, 2, 40)
    assert detection_limit(first, ["missing"], 0.01, 0.02, 3, 2) is None
