"""The engine's choice of the loads an effect acts on: leave-one-flight-out error against an
independent computation, and an effect on one load kept off the others."""

from __future__ import annotations

import numpy as np

from fwid.diagnosis._attribution import (Engine, OnLoads, acting, numbers_of,
                                         one_standard_error, simplest_best, units)
from fwid.diagnosis._catalogue import actuator_filter, get_effect
from fwid.diagnosis._catalogue.nonlinear_aero import columns_of
from fwid.diagnosis._signals import Signals


def _smooth(rng, n, dt):
    x = np.cumsum(rng.normal(size=n)) * np.sqrt(dt)
    k = np.ones(25) / 25
    return np.convolve(x - x.mean(), k, mode="same")


def _flight(rng, k, quadratic_on_m=2.0, n=600, dt=0.01):
    slow = {s: _smooth(rng, n, dt) for s in ("u", "w", "q", "de")}
    u, w, q, de = (slow[s] for s in ("u", "w", "q", "de"))
    noise = {ld: 0.02 * rng.normal(size=n) for ld in ("X", "Z", "M")}
    averaged = {"X": -0.3 * u + 0.1 * w + 1.0 + noise["X"],
                "Z": -0.8 * w + 0.2 * q - 0.4 * de + noise["Z"],
                "M": -0.5 * q - 0.3 * w + 0.6 * de + quadratic_on_m * w * np.abs(w)
                + noise["M"]}
    phase = 2 * np.pi * 12.0 * np.arange(n) * dt
    flapping = {ld: 0.01 * rng.normal(size=n) for ld in ("X", "Z", "M")}
    return Signals(name=f"f{k}", t=np.arange(n) * dt, dt=dt, phase=phase, f_mean=12.0,
                   f_spread=0.0, slow=slow, fast={s: np.zeros(n) for s in slow},
                   loads={"averaged": averaged, "flapping": flapping},
                   manoeuvre=np.ones(n, bool))


def _engine(rng, count=6, **kw):
    return Engine(units([_flight(rng, k, **kw) for k in range(count)]), ("X", "Z", "M"))


def _refitted(eng, idx, k, ch, model) -> float:
    """Unit `k`'s error in `ch` under `model` refitted here on the other units of `idx`."""
    others = [i for i in idx if i != k]
    a = np.concatenate([eng.units[i].projector["averaged"](eng.design(i, ch, model))
                        for i in others])
    b = np.concatenate([eng.units[i].projector["averaged"](eng.target(i, ch)) for i in others])
    theta, *_ = np.linalg.lstsq(a, b, rcond=None)
    return float(np.sum(eng.residual(k, ch, theta, model) ** 2))


def test_leave_one_flight_out_error_matches_refitting_without_each_flight():
    rng = np.random.default_rng(3)
    eng = _engine(rng)
    idx = tuple(range(6))
    nl = get_effect("nonlinear-aero").bound(eng, idx)  # its splines over these flights
    model = ((nl, nl.variants[0]),)
    for ch in (("M", "averaged"), ("Z", "averaged")):
        ref = sum(_refitted(eng, idx, k, ch, model) for k in idx)
        assert np.isclose(eng.loo_error(idx, ch, model), ref, rtol=1e-8)


def test_an_effect_on_one_load_acts_on_that_load_only():
    rng = np.random.default_rng(4)
    eng = _engine(rng)
    idx = tuple(range(6))
    sigma2 = eng.mean_square(idx)
    nl = get_effect("nonlinear-aero").bound(eng, idx)
    v = eng.choose(idx, (), nl, sigma2)
    assert isinstance(v, OnLoads) and v.loads == ("M",)
    # where it does not act, the design is the baseline's
    assert acting(((nl, v),), ("X", "averaged")) == ()
    assert eng.design(0, ("X", "averaged"), ((nl, v),)).shape[1] == 4
    # the family's size (`Effect.sized`): the member chosen by leave-one-flight-out error,
    # `w`'s smooth odd shape (`M` has `w |w|`), not every variable's finest shapes
    assert v.variant.which == (1,) and v.variant.df >= 2, v.variant
    size = columns_of(eng.units[0].signals.slow, "lon", v.variant).shape[1]
    assert eng.design(0, ("M", "averaged"), ((nl, v),)).shape[1] == 4 + size
    # with no such term anywhere, it seldom acts anywhere: its columns only fit noise, which
    # raises the error on the flight left out (30 seeds x 3 loads: 1 chosen when written)
    chosen = 0
    for seed in range(30):
        e0 = _engine(np.random.default_rng(100 + seed), quadratic_on_m=0.0)
        chosen += len(e0.choose(idx, (), get_effect("nonlinear-aero").bound(e0, idx),
                                e0.mean_square(idx)).loads)
    assert chosen <= 4


def test_an_effect_of_the_quiet_axis_is_kept_off_its_loads():
    """Loads of the axis that was not manoeuvred (here M, by `own`) take only the effects whose
    columns there carry the manoeuvre (`Effect.crosses_axes`): the quadratic term on M is not
    taken up although it is there, the deflection's lag replaces it on the own loads only,
    and the coupling and the flapping frequency may act anywhere."""
    rng = np.random.default_rng(4)
    flights = [_flight(rng, k) for k in range(6)]
    eng = Engine(units(flights), ("X", "Z", "M"), own=("X", "Z"))
    idx = tuple(range(6))
    sigma2 = eng.mean_square(idx)
    nl = get_effect("nonlinear-aero").bound(eng, idx)
    assert eng.allowed(nl) == ("X", "Z")
    assert "M" not in eng.choose(idx, (), nl, sigma2).loads
    assert eng.choose(idx, (), get_effect("actuator-dynamics"), sigma2).loads == ("X", "Z")
    for name in ("lon-lat-coupling", "flap-frequency", "flap-coupling"):
        assert eng.allowed(get_effect(name)) == ("X", "Z", "M")
    # by default every load is the engine's own, and the quadratic term on M is found
    full = Engine(units(flights), ("X", "Z", "M"))
    assert full.choose(idx, (), nl, full.mean_square(idx)).loads == ("M",)


def test_a_member_that_acts_as_a_simpler_one_is_not_chosen():
    """A small deflection through a plain lag never reaches the rate limits of the family's
    rate-limited lags, which then fit exactly as well as the lag: the lag (listed first) is
    chosen, not a rate limit that the data never showed."""
    rng = np.random.default_rng(5)
    fls = []
    for k in range(5):
        fl = _flight(rng, k, quadratic_on_m=0.0)
        de = 0.01 * fl.slow["de"]
        fl.slow["de"] = de
        assert np.max(np.abs(np.diff(de))) / fl.dt < 0.5  # below every rate limit in the grid
        u, w, q = (fl.slow[s] for s in ("u", "w", "q"))
        acting_de = actuator_filter(de, fl.dt, ("lag", 0.05))
        for ld, (cu, cw, cq, cd) in {"X": (-0.3, 0.1, 0.0, 0.0), "Z": (0.0, -0.8, 0.2, -40.0),
                                     "M": (0.0, -0.3, -0.5, 60.0)}.items():
            fl.loads["averaged"][ld] = (cu * u + cw * w + cq * q + cd * acting_de
                                        + 0.02 * rng.normal(size=fl.n))
        fls.append(fl)
    eng = Engine(units(fls), ("X", "Z", "M"))
    e = get_effect("actuator-dynamics")
    idx = tuple(range(5))
    sigma2 = {ch: 1.0 for ch in eng.channels("averaged")}
    costs = [sum(eng.loo_error(idx, ch, ((e, v),)) for ch in eng.channels("averaged"))
             for v in e.variants]
    ties = [v for v, c in zip(e.variants, costs) if np.isclose(c, min(costs), rtol=1e-9)]
    assert ("lag", 0.05) in ties and any(v[0] == "rate-limit" for v in ties)
    assert eng.best_variant(idx, (), e, sigma2) == ("lag", 0.05)
    assert simplest_best([3.0, 1.0, 1.0 + 1e-12, 0.5 + 1e-10, 0.5]) == 3


def test_the_one_standard_error_rule_takes_the_fewest_columns_near_the_best():
    best = np.array([10.0, 12.0, 8.0, 10.0])  # total 40, standard error of the total 3.27
    se = np.std(best, ddof=1) * 2.0
    errors = [best, best + 0.7, best + 0.9, best - 0.1, best + 5.0]
    sizes = [8, 4, 4, 12, 1]
    # within 40.4 + se: members 0 to 3; the fewest columns: 1 and 2; of them the least error
    assert 3 * 0.9 < se and 4 * 5.0 > se
    assert one_standard_error(errors, sizes) == 1
    # members of one size: the least error, as before the rule
    assert one_standard_error(errors, [1] * 5) == 3
    # nothing near the best: the best
    assert one_standard_error([best, best + 10.0], [5, 1]) == 0
    # a member's size counts the numbers it is chosen with: a rate-limited lag within the
    # noise of a plain one is not preferred to it
    lag, limited = ("lag", 0.05), ("rate-limit", 0.05, 1.7)
    assert (numbers_of(lag), numbers_of(limited), numbers_of(None)) == (1, 2, 0)
    assert numbers_of(("saturation", 0.02, 0.1, "before")) == 2
    assert one_standard_error([best + 0.5, best],
                              [1 + numbers_of(lag), 1 + numbers_of(limited)]) == 0


def test_the_member_is_the_rules_choice_on_refitted_leave_one_out_errors():
    rng = np.random.default_rng(5)
    eng = _engine(rng, count=8, quadratic_on_m=0.3)
    idx = tuple(range(8))
    nl = get_effect("nonlinear-aero").bound(eng, idx)
    chans = eng.channels("averaged")
    errors, sizes = [], []
    for v in nl.variants:  # each flight scored by a fit to the others, refitted here
        model = ((nl, v),)
        errors.append(np.array([sum(_refitted(eng, idx, k, ch, model) for ch in chans)
                                for k in idx]))
        sizes.append(sum(eng.design(0, ch, model).shape[1] for ch in chans))
    chosen = eng.best_variant(idx, (), nl, {ch: 1.0 for ch in chans})
    assert chosen == nl.variants[one_standard_error(errors, sizes)]
    least = int(np.argmin([e.sum() for e in errors]))
    assert chosen.which == nl.variants[least].which == (1,)  # the bend of w
    assert sizes[nl.variants.index(chosen)] < sizes[least]  # smaller, within its noise


def _with_term(seed: int, term, count: int = 6, scale: float = 1.0) -> Engine:
    """`count` flights of `_flight` without its quadratic term, with `term(u, w)` (a dict by
    load) added, each part scaled to `scale` times the RMS of the loads' noise (0.02)."""
    rng = np.random.default_rng(seed)
    flights = []
    for k in range(count):
        fl = _flight(rng, k, quadratic_on_m=0.0)
        for ld, g in term(fl.slow["u"], fl.slow["w"]).items():
            fl.loads["averaged"][ld] = fl.loads["averaged"][ld] + scale * 0.02 * g / np.std(g)
        flights.append(fl)
    return Engine(units(flights), ("X", "Z", "M"))


def _chosen(eng: Engine) -> OnLoads:
    idx = tuple(range(len(eng.units)))
    return eng.choose(idx, (), get_effect("nonlinear-aero").bound(eng, idx),
                      eng.mean_square(idx))


def test_the_member_explains_the_loads_the_family_acts_on():
    """A bend of Z in w alone, as strong as the noise, on six flights: wherever the family
    acts, its member is a function of w (chosen on the loads it acts on, not on the noise of
    X and M), and it acts on Z in most draws (the member may not be one that adds nothing
    there)."""
    found = 0
    for seed in range(10):
        v = _chosen(_with_term(seed, lambda u, w: {"Z": w * w}))
        assert v.loads in ((), ("Z",)), (seed, v.loads)
        if v.loads:
            found += 1
            assert 1 in v.variant.which and v.variant.df >= 1, (seed, v.variant)
    assert found >= 6, found


def test_a_product_and_quadratic_loads_are_found_on_six_flights():
    """A `u w` product on M, and loads quadratic in u (X) and w (Z), each as strong as the
    noise: the family acts on the load that holds the term in every draw of six flights,
    with a member that holds it (the products; mostly a function of u, among the members
    that lower the error of every load the family acts on: 9 of 10 when written)."""
    of_u = 0
    for seed in range(10):
        v = _chosen(_with_term(seed, lambda u, w: {"M": u * w}))
        assert v.loads == ("M",) and v.variant.products, (seed, v)
        v = _chosen(_with_term(seed, lambda u, w: {"X": u * u, "Z": w * w}))
        assert "X" in v.loads and v.variant.df >= 1, (seed, v)
        of_u += 0 in v.variant.which
    assert of_u >= 8, of_u


def test_an_admitted_effect_never_acts_on_no_load():
    """An effect the selection admitted (its cross-fit acted on M) whose fit on the training
    flights alone acts on no load is fitted on M, with a member that lowers M's error there
    (`Engine.on_loads`), not reported with `acts_on` empty; one not admitted stays as fitted."""
    from types import SimpleNamespace

    from fwid.diagnosis._scores import Scores

    eng = _with_term(0, lambda u, w: {"M": u * w}, scale=0.1)  # a tenth of the noise
    idx = tuple(range(6))
    nl = get_effect("nonlinear-aero").bound(eng, idx)
    s2 = eng.mean_square(idx)
    assert eng.choose(idx, (), nl, s2).loads == ()  # the training flights alone miss it...
    scores = SimpleNamespace(c=SimpleNamespace(engine=eng, train_idx=idx, sigma2=s2,
                                               loads=("X", "Z", "M")))
    admitted = SimpleNamespace(variants=(OnLoads(nl.variants[0], ()),
                                         OnLoads(nl.variants[4], ("M",))))
    v = Scores.fitted(scores, (), nl, admitted)  # ...which the other half found
    assert v.loads == ("M",)
    assert eng.lowers(idx, (), nl, ("M", "averaged"), v.variant) and v.variant.products
    assert Scores.fitted(scores, (), nl, None).loads == ()
