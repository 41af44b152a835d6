"""Forms of the injected effects, two effects at once, the strength yardstick and randomised
vehicles."""

import numpy as np
import pytest

from fwid.synth import (
    DELFLY,
    EFFECTS,
    FORMS,
    OUT_OF_CATALOGUE,
    RANDOM_PARAMS,
    Effect,
    effect_noise_ratio,
    form_axes,
    random_vehicle,
    simulate_flight,
)

LON, LAT = ("X", "Z", "M"), ("Y", "L", "N")
ALL_FORMS = [(e, f) for e in EFFECTS[1:] + OUT_OF_CATALOGUE for f in FORMS[e]]
SHORT = {"duration": 2.5, "input": "doublet"}


def _columns(fl):
    return {k: v for k, v in fl.items() if k != "meta"}


@pytest.fixture(scope="module")
def base():
    return {ax: simulate_flight(axis=ax, seed=4, noise=0.0, **SHORT) for ax in ("lon", "lat")}


def test_every_effect_has_at_least_four_forms():
    for e in EFFECTS[1:]:
        assert len(FORMS[e]) >= 4, e
    assert set(OUT_OF_CATALOGUE) == {"turbulence", "cg-offset", "battery-sag"}
    assert Effect("sensor-offset").name == "time-offset"  # the old name is an alias
    assert Effect("flap-coupling").form == "amplitude"  # the default is the original form
    with pytest.raises(ValueError):
        Effect("flap-coupling", form="wobble")


@pytest.mark.parametrize("effect,form", ALL_FORMS)
def test_form_at_zero_strength_is_none(effect, form):
    none = simulate_flight(axis="lon", seed=1, **SHORT)
    off = simulate_flight(axis="lon", seed=1, effect=effect, form=form, strength=0.0, **SHORT)
    for c, v in _columns(none).items():
        np.testing.assert_array_equal(v, off[c])


def _dload(base, on, load):
    return np.max(np.abs(on["meta"]["loads_true"][load] - base["meta"]["loads_true"][load]))


@pytest.mark.parametrize("effect,form", ALL_FORMS)
def test_form_changes_the_flight_on_its_axes(effect, form, base):
    for ax in form_axes(effect, form):
        on = simulate_flight(axis=ax, seed=4, noise=0.0, effect=effect, form=form, **SHORT)
        ref = np.max(np.abs(on["meta"]["loads_effect"]["M" if ax == "lon" else "L"]))
        eff = max(np.std(v) for v in on["meta"]["loads_effect"].values())
        assert eff > 0 and np.isfinite(ref), (ax, eff)
        if effect == "time-offset":
            assert np.max(np.abs(on["de"] - base[ax]["de"]) + np.abs(on["dr"] - base[ax]["dr"])) > 0
        else:
            assert max(_dload(base[ax], on, k) for k in LON + LAT) > 0
        assert on["meta"]["truth"]["form"] == form


@pytest.mark.parametrize("form,ax,hit,untouched", [
    ("lat-to-lon", "lat", LON, ()),
    ("lon-to-lat", "lon", LAT, LON),
    ("rates", "lon", LAT, ()),
])
def test_lon_lat_coupling_direction(form, ax, hit, untouched, base):
    """Each direction hits the other axis's loads; a manoeuvre the form does not show on
    gives the flight without the effect."""
    on = simulate_flight(axis=ax, seed=4, noise=0.0, effect="lon-lat-coupling", form=form, **SHORT)
    extra = on["meta"]["loads_effect"]
    for k in hit:
        assert np.std(extra[k]) > 0, k
    other = "lat" if ax == "lon" else "lon"
    off = simulate_flight(axis=other, seed=4, noise=0.0, effect="lon-lat-coupling", form=form,
                          **SHORT)
    assert form_axes("lon-lat-coupling", form) == (ax,)
    for c, v in _columns(base[other]).items():
        np.testing.assert_array_equal(v, off[c])
    # lat-to-lon in a lat flight leaves the lateral loads' effect part at zero, and so on
    for k in LAT if form == "lat-to-lon" else LON:
        assert np.max(np.abs(extra[k])) < 1e-12 * max(1.0, np.max(np.abs(extra[hit[0]]))), k


@pytest.mark.parametrize("form", FORMS["nonlinear-aero"])
def test_nonlinear_aero_acts_on_both_axes(form, base):
    for ax, loads in (("lon", LON), ("lat", LAT)):
        on = simulate_flight(axis=ax, seed=4, noise=0.0, effect="nonlinear-aero", form=form,
                             **SHORT)
        assert max(np.std(on["meta"]["loads_effect"][k]) for k in loads) > 1e-5, (ax, form)


def test_flap_coupling_forms_act_on_the_flapping_band(base):
    for form in FORMS["flap-coupling"]:
        on = simulate_flight(axis="lon", seed=4, noise=0.0, effect="flap-coupling", form=form,
                             **SHORT)
        d = on["meta"]["loads_flap"]["M"] - base["lon"]["meta"]["loads_flap"]["M"]
        assert np.std(d) > 0.05 * np.std(base["lon"]["meta"]["loads_flap"]["M"]), form
    # shape leaves the fundamental alone: at zero u, w, v, r it changes nothing
    from fwid.synth._effects._flapping import Shape

    F, H, Q = np.ones(6), np.ones((3, 6)), np.zeros((3, 6))
    np.testing.assert_array_equal(Shape(1.0, DELFLY).flapping(np.zeros(9), np.zeros(2), F, H, Q), F)


def test_actuator_forms_lag_the_command_and_keep_the_measured_column():
    kw = {"axis": "lon", "noise": 0.0, "input": "pulse", "unit": 1.0, "amplitude": 0.1,
          "ripple": False}
    for form in FORMS["actuator-dynamics"]:
        fl = simulate_flight(effect="actuator-dynamics", form=form, **kw)
        m = fl["meta"]
        k0 = m["first_input"]
        ue, uc = m["u_eff"][:, 0], m["u_cmd"][:, 0]
        c = Effect("actuator-dynamics", form=form).coefficients()
        # where it settles: a travel limit saturates the step, play leaves it short by the band
        settled = (c["limit_de"] * np.tanh(uc / c["limit_de"]) if form == "saturation"
                   else uc - c["play_de"] if form == "backlash" else uc)
        assert np.all(ue[:k0] == 0.0)
        assert ue[k0 + 1] < uc[k0 + 1] - 1e-3, form  # lags right after the step
        assert abs(ue[k0 + 150] - settled[k0 + 150]) < 2e-3, form  # and settles
        np.testing.assert_allclose(fl["de"] - m["trim"]["de0"], uc, atol=1e-15)
    d = simulate_flight(effect="actuator-dynamics", form="delay", **kw)["meta"]
    T = Effect("actuator-dynamics", form="delay").coefficients()["delay"]
    n = round(T * 200)
    np.testing.assert_allclose(d["u_eff"][n:, 0], d["u_cmd"][:-n, 0], atol=1e-12)


def test_backlash_holds_on_a_reversal_and_saturation_levels_off():
    """`backlash`: the deflection does not move while the command is within the play of it
    (hysteresis: after a reversal it settles short by the play, from the other side);
    `saturation`: a larger command gains less deflection."""
    from fwid.synth._effects._actuator import Backlash

    kw = {"axis": "lon", "noise": 0.0, "input": "doublet", "unit": 1.0, "ripple": False}
    fl = simulate_flight(effect="actuator-dynamics", form="backlash", amplitude=0.1, **kw)
    m = fl["meta"]
    ue, uc = m["u_eff"][:, 0], m["u_cmd"][:, 0]
    bl = Backlash(1.0, DELFLY)
    b = bl.c["play_de"]
    u = np.array([0.05, 0.0])
    assert np.all(bl.aux_rhs(None, u + [0.9 * b, 0.0], u, u) == 0.0)  # within the play
    assert bl.aux_rhs(None, u + [2 * b, 0.0], u, u)[0] == pytest.approx(b / bl.c["tau"])
    turn = m["first_input"] + 200  # the doublet reverses after its 1 s unit
    assert abs(ue[turn - 1] - (uc[turn - 1] - b)) < 2e-3  # short by the play from below
    assert abs(ue[turn + 150] - (uc[turn + 150] + b)) < 2e-3  # then from above
    small, large = (simulate_flight(effect="actuator-dynamics", form="saturation",
                                    amplitude=a, **kw)["meta"]["u_eff"][:, 0] for a in (0.02, 0.2))
    k = m["first_input"] + 150
    assert 0.95 < small[k] / 0.02 <= 1.0 and large[k] / 0.2 < 0.5


def test_new_forms_stay_bounded_at_strength_two():
    """8 s flights of the forms added last do not run away at strength 2: the attitude stays
    well below pi, within 0.8 rad or 1.5 times its swing without the effect (a lateral doublet
    without any effect rolls by ~1.3 rad in 8 s)."""
    def swing(fl):
        c = fl["meta"]["clean"]
        return max(np.max(np.abs(c[k] - c[k][0])) for k in ("theta", "phi"))

    kw = {"seed": 1, "duration": 8.0, "input": "doublet", "vehicle": random_vehicle(1)}
    without = {ax: swing(simulate_flight(axis=ax, **kw)) for ax in ("lon", "lat")}
    for e, f in ALL_FORMS:
        if e not in EFFECTS or FORMS[e].index(f) < (6 if e == "actuator-dynamics" else 4):
            continue
        for ax in form_axes(e, f):
            got = swing(simulate_flight(axis=ax, effect=e, form=f, strength=2.0, **kw))
            assert np.isfinite(got) and got < max(1.5 * without[ax], 0.8), (e, f, ax, got)


def test_sensor_offset_shifts_the_measured_control_the_other_way():
    """The logged column trails the true deflection, so the response LEADS it."""
    kw = {"axis": "lon", "noise": 0.0, "input": "pulse", "unit": 1.0, "amplitude": 0.1,
          "ripple": False}
    base = simulate_flight(**kw)
    fl = simulate_flight(effect="time-offset", **kw)
    T = Effect("time-offset").coefficients()["offset"]
    n = round(T * 200)
    np.testing.assert_allclose(fl["de"][n:], base["de"][:-n], atol=1e-12)
    np.testing.assert_array_equal(fl["meta"]["u_eff"], base["meta"]["u_eff"])  # acts at once
    np.testing.assert_array_equal(fl["q"], base["q"])  # the motion is that of no effect
    k0 = base["meta"]["first_input"]
    assert fl["de"][k0 + n - 1] == base["de"][0] and base["de"][k0 + 1] > base["de"][0]


def test_flap_frequency_loads_follow_the_true_frequency():
    """`thrust`: the load the effect adds is `c (f - f0)` at the true frequency (the sidecar's
    clean `f`), exactly; `lagged` is the same signal late (it correlates best at a lag)."""
    kw = {"axis": "lon", "noise": 0.0, "seed": 3}
    fl = simulate_flight(effect="flap-frequency", form="thrust", **kw)
    c = Effect("flap-frequency", form="thrust").coefficients()
    df = fl["meta"]["clean"]["f"] - DELFLY.f0
    for load, k in (("X", "cx"), ("Z", "cz"), ("M", "cm")):
        np.testing.assert_allclose(fl["meta"]["loads_effect"][load], c[k] * df, atol=1e-12)
    lag = simulate_flight(effect="flap-frequency", form="lagged", **kw)["meta"]["loads_effect"]["X"]
    x = (lag - lag.mean()) / lag.std()
    y = (df - df.mean()) / df.std()
    xc = [np.mean(x[k:] * y[:len(y) - k]) for k in range(0, 120, 5)]
    assert 10 <= 5 * int(np.argmax(xc)) <= 60  # 0.05-0.3 s at 200 Hz (tau = 0.15 s)


def test_clock_drift_offset_grows_over_the_flight():
    """`clock-drift`: the logged column is `col(t - k t)`: no offset at the start, `k t` later."""
    kw = {"axis": "lon", "noise": 0.0, "ripple": False}
    base = simulate_flight(**kw)
    fl = simulate_flight(effect="time-offset", form="clock-drift", **kw)
    k = Effect("time-offset", form="clock-drift").coefficients()["drift"]
    t = base["t"]
    np.testing.assert_allclose(fl["de"], np.interp(t - k * t, t, base["de"]), atol=1e-12)


def test_resync_offset_is_a_sawtooth():
    """`resync`: the offset grows at `k` and snaps back to zero every 1.5 s."""
    kw = {"axis": "lon", "noise": 0.0, "ripple": False}
    base = simulate_flight(**kw)
    fl = simulate_flight(effect="time-offset", form="resync", **kw)
    k = Effect("time-offset", form="resync").coefficients()["drift"]
    t = base["t"]
    T = k * np.mod(t + 1.0, 1.5)
    assert T.max() == pytest.approx(1.5 * k, rel=0.01) and np.sum(np.diff(T) < 0) == 3
    np.testing.assert_allclose(fl["de"], np.interp(t - T, t, base["de"]), atol=1e-12)


def test_saturating_thrust_levels_off_and_harmonic_moves_the_second_harmonic_only():
    kw = {"axis": "lon", "noise": 0.0, "seed": 3}
    fl = simulate_flight(effect="flap-frequency", form="saturating", **kw)
    c = Effect("flap-frequency", form="saturating").coefficients()
    df = fl["meta"]["clean"]["f"] - DELFLY.f0
    np.testing.assert_allclose(fl["meta"]["loads_effect"]["X"], c["cx"] * 0.05 * np.tanh(df / 0.05),
                               atol=1e-12)
    from fwid.synth._effects._flapping import Harmonic

    xc = np.zeros(9)
    xc[2] = 0.1
    F, H, Q = np.ones(6), np.arange(18.0).reshape(3, 6), np.zeros((3, 6))
    out = Harmonic(1.0, DELFLY).flapping(xc, np.zeros(2), F, H, Q)
    np.testing.assert_allclose(out - F, 0.1 * Harmonic.COEFFICIENTS["hw"] * H[1])


def test_wagner_lag_is_two_poles():
    """`wagner`: after a step of the incidence the lagged load deficit decays with a fast and a
    slow time constant (Jones' two-pole indicial response), starting from the whole lagging
    fraction."""
    from fwid.synth._effects._aero import Wagner

    w = Wagner(1.0, DELFLY)
    c = w.c
    x = np.zeros(9)
    x[2] = 1.0
    aux = np.zeros(18)  # the lagged states still at rest
    d0 = w.extra_loads(x, np.zeros(2), aux)
    aux_late = np.concatenate([x * (1 - np.exp(-0.1 / c["tau1"])),
                               x * (1 - np.exp(-0.1 / c["tau2"]))])
    d1 = w.extra_loads(x, np.zeros(2), aux_late)
    expect = c["a1"] * np.exp(-0.1 / c["tau1"]) + (1 - c["a1"]) * np.exp(-0.1 / c["tau2"])
    np.testing.assert_allclose(d1, expect * d0, rtol=1e-12)
    assert d0[2] != 0 and np.all(w.aux_rhs(x, None, None, aux)[:9] == x / c["tau1"])


def test_two_effects_compose():
    a = simulate_flight(seed=2, noise=0.0, effect="flap-coupling", form="control", **SHORT)
    b = simulate_flight(seed=2, noise=0.0, effect="actuator-dynamics", form="delay", **SHORT)
    ab = simulate_flight(seed=2, noise=0.0, effect=("flap-coupling", "actuator-dynamics"),
                         form=("control", "delay"), **SHORT)
    same = simulate_flight(seed=2, noise=0.0, effect="flap-coupling+actuator-dynamics",
                           form="control+delay", **SHORT)
    np.testing.assert_array_equal(ab["q"], same["q"])
    np.testing.assert_array_equal(ab["meta"]["u_eff"], b["meta"]["u_eff"])  # the delay acts
    assert not np.array_equal(ab["meta"]["loads_flap"]["M"], b["meta"]["loads_flap"]["M"])
    assert not np.array_equal(ab["q"], a["q"])
    t = ab["meta"]["truth"]
    assert t["effect"] == "flap-coupling+actuator-dynamics" and t["form"] == "control+delay"
    assert set(t["effect_coefficients"]) == {"flap-coupling", "actuator-dynamics"}
    # one part at strength 0 is the other alone
    half = simulate_flight(seed=2, noise=0.0, effect=("flap-coupling", "actuator-dynamics"),
                           form=("control", "delay"), strength=(1.0, 0.0), **SHORT)
    np.testing.assert_array_equal(half["q"], a["q"])
    with pytest.raises(ValueError):
        Effect(("flap-coupling", "flap-coupling"))
    with pytest.raises(ValueError):
        Effect(("flap-coupling", "actuator-dynamics"), form=("control",))


def test_effect_noise_ratio_sizes_strength_one():
    """Strength 1 is about as strong as the noise on its loads (banded yardstick)."""
    for e, f in (("flap-coupling", "phase"), ("nonlinear-aero", "cubic"),
                 ("lon-lat-coupling", "lon-to-lat"), ("nonlinear-aero", "one-sided"),
                 ("lon-lat-coupling", "gyroscopic")):
        r = effect_noise_ratio(e, f)  # the default manoeuvre: 3211, 4.5 s, 200 Hz
        assert 0.7 < r["max"] < 2.0, (e, f, r["max"])
    none = effect_noise_ratio("nonlinear-aero", strength=0.0, axes=("lon",), duration=3.0)
    assert none["max"] < 1e-6


def test_random_vehicle_is_stable_within_spread_and_deterministic():
    for seed in range(20):
        v = random_vehicle(seed)
        for a in ("lon", "lat"):
            assert np.max(v.eigenvalues(a).real) < 0
        ratio = np.array([getattr(v, k) / getattr(DELFLY, k) for k in RANDOM_PARAMS])
        assert np.all((ratio >= 0.7 - 1e-12) & (ratio <= 1.3 + 1e-12))
        assert v.mass == DELFLY.mass and v.theta0 == DELFLY.theta0
    assert random_vehicle(3) == random_vehicle(3) and random_vehicle(3) != random_vehicle(4)
    assert random_vehicle(5, spread=0.0) == DELFLY
