"""`actuator-dynamics` as a family of causal filters (`_catalogue.actuator_filter`), checked
against continuous-time responses computed independently."""

import numpy as np
import pytest
from scipy.signal import lsim

from fwid.diagnosis._catalogue import (ACTUATOR_FILTERS, CATALOGUE, actuator_filter,
                                       filter_text, get_effect)

DT = 0.001
T = np.arange(0.0, 0.6, DT)


def _step(at=0.05, size=0.1):
    return np.where(T >= at, size, 0.0)


def test_second_order_matches_the_continuous_servo():
    fn, zeta = 8.0, 0.5
    wn = 2 * np.pi * fn
    x = _step()
    y = actuator_filter(x, DT, ("second-order", fn, zeta))
    _, ref, _ = lsim(([wn * wn], [1.0, 2 * zeta * wn, wn * wn]), x, T)
    assert np.max(np.abs(y - ref)) < 0.01 * 0.1 * 3  # the bilinear map is a step behind at most
    assert y.max() > 0.11  # it overshoots (damping 0.5), as a first-order lag cannot


def test_lag_and_delay_members_keep_their_shapes():
    x = _step()
    y = actuator_filter(x, DT, ("lag-delay", 0.04, 0.03))
    t = T - 0.05 - 0.03
    ref = np.where(t >= 0, 0.1 * (1 - np.exp(-np.maximum(t, 0) / 0.04)), 0.0)
    assert np.max(np.abs(y - ref)) < 3e-3
    assert np.all(y[T < 0.05 + 0.03 - DT] == 0.0)  # nothing acts before the delay


def test_rate_limit_caps_the_slope_and_is_a_lag_below_it():
    x = _step(size=0.2)
    y = actuator_filter(x, DT, ("rate-limit", 0.02, 1.0))
    assert np.max(np.diff(y)) <= 1.0 * DT + 1e-15
    assert y[np.searchsorted(T, 0.15)] == pytest.approx(0.1, abs=2e-3)  # 1 rad/s for 0.1 s
    fast = actuator_filter(x, DT, ("rate-limit", 0.02, 1e6))
    t = np.maximum(T - 0.05, 0)
    np.testing.assert_allclose(fast, np.where(T >= 0.05, 0.2 * (1 - np.exp(-t / 0.02)), 0.0),
                               atol=0.2 * DT / 0.02)


def test_asymmetric_lag_rises_and_falls_with_its_own_time_constants():
    on, off = 50, 400
    x = np.zeros_like(T)
    x[on:off] = 0.1
    y = actuator_filter(x, DT, ("asymmetric", 0.03, 0.08))
    rise = y[on + 30] / 0.1
    fall = y[off + 80] / y[off - 1]
    assert rise == pytest.approx(1 - np.exp(-1), abs=0.02)
    assert fall == pytest.approx(np.exp(-1), abs=0.02)
    # the opposite member falls fast
    z = actuator_filter(x, DT, ("asymmetric", 0.08, 0.03))
    assert z[on + 30] < y[on + 30] and z[off + 30] / z[off - 1] < 0.4


def test_actuator_family_is_chosen_by_held_out_error_and_every_member_runs():
    e = get_effect("actuator-dynamics")
    assert e.sized and e.replaces_input and e.variants == ACTUATOR_FILTERS
    kinds = {v[0] for v in ACTUATOR_FILTERS}
    assert kinds == {"lag", "delay", "lag-delay", "second-order", "rate-limit", "asymmetric",
                     "saturation", "dead-band", "backlash"}
    x = np.sin(2 * np.pi * 2 * T)
    for v in ACTUATOR_FILTERS:
        y = actuator_filter(x, DT, v)
        assert y.shape == x.shape and np.all(np.isfinite(y)), v
        assert filter_text(v)
    assert {c.name for c in CATALOGUE if c.sized} == {
        "nonlinear-aero", "actuator-dynamics", "unsteady-aero", "flap-coupling"}


def test_hammerstein_and_wiener_saturations_differ_and_are_lags_below_the_limit():
    """A saturation before the lag (Hammerstein) clips the input, after it (Wiener) the
    output; below the limit both are the plain lag."""
    x = _step(size=0.2)
    lag = actuator_filter(x, DT, ("lag", 0.03))
    before = actuator_filter(x, DT, ("saturation", 0.03, 0.1, "before"))
    after = actuator_filter(x, DT, ("saturation", 0.03, 0.1, "after"))
    np.testing.assert_allclose(before, lag / 2, atol=1e-12)  # the clipped step, lagged
    np.testing.assert_allclose(after, np.minimum(lag, 0.1), atol=1e-12)
    small = _step(size=0.05)
    for order in ("before", "after"):
        np.testing.assert_allclose(actuator_filter(small, DT, ("saturation", 0.03, 0.1, order)),
                                   actuator_filter(small, DT, ("lag", 0.03)), atol=1e-12)


def test_backlash_holds_until_the_input_crosses_its_play():
    from fwid.diagnosis._catalogue._filters import backlash

    x = 0.1 * np.sin(2 * np.pi * 2 * T)
    y = backlash(x, 0.04)
    assert np.max(np.abs(y - x)) <= 0.02 + 1e-15
    turn = np.argmax(x)  # after the top, the output holds while the input falls by the play
    end = turn + np.argmax(x[turn:] < x[turn] - 0.04)
    assert np.all(np.diff(y[turn:end]) == 0.0) and y[end + 5] < y[turn]


def _signals(slow, fast, dt=0.01, f=12.5):
    """A flight's `Signals` holding only the elevator, split into `slow` and `fast`, flapping
    at `f` Hz; its whole record is the elevator as commanded (`_signals.commanded`)."""
    import dataclasses

    from fwid.diagnosis._signals import Signals, commanded

    n = len(slow)
    phase = 2 * np.pi * f * np.arange(n) * dt
    fields = {f.name: None for f in dataclasses.fields(Signals)}
    fields.update(name="x", t=np.arange(n) * dt, dt=dt, phase=phase, slow={"de": slow},
                  fast={"de": fast}, cutoff=5.0, whole={"de": commanded(slow + fast, phase)},
                  edge=0)
    return Signals(**fields)


def test_the_nonlinear_members_are_sized_on_the_commanded_deflection():
    """Saturations on the largest commanded deflection, rate limits as the times to cross it;
    the flapping ripple of the measured column (here 12.5 Hz, locked to the phase) counts in
    neither."""
    from types import SimpleNamespace

    from fwid.diagnosis._catalogue.actuator_dynamics import RATE_LIMITS

    e = get_effect("actuator-dynamics")
    t = np.arange(1001) * 0.01
    slow = 0.2 * np.sin(2 * np.pi * 0.5 * t)
    fast = 0.05 * np.sin(2 * np.pi * 12.5 * t + 0.3)  # the ripple, a quarter of the command
    sig = _signals(slow, fast)
    engine = SimpleNamespace(own=("X", "Z", "M"), units=[SimpleNamespace(signals=sig)])
    bound = e.bound(engine, (0,))
    sizes = sorted({v[2] for v in bound.variants if v[0] == "saturation"})
    scale = np.percentile(np.abs(slow), 99.0)
    np.testing.assert_allclose(sizes, [0.5 * scale, 0.75 * scale], rtol=1e-3)
    rates = sorted({v[2] for v in bound.variants if v[0] == "rate-limit"})
    np.testing.assert_allclose(rates, sorted(scale / T for T in RATE_LIMITS), rtol=1e-3)
    sized = ("saturation", "dead-band", "backlash", "rate-limit")
    assert [v for v in bound.variants if v[0] not in sized] \
        == [v for v in e.variants if v[0] not in sized]
    # a control that never moves: nothing to size, those members go
    still = SimpleNamespace(own=("X", "Z", "M"), units=[SimpleNamespace(
        signals=_signals(np.zeros(100), np.zeros(100)))])
    assert {v[0] for v in e.bound(still, (0,)).variants}.isdisjoint(sized)


def test_the_commanded_deflection_is_the_measured_one_less_its_flapping_ripple():
    """Three harmonics of the phase (a drifting wing beat) come off; a 3211's steps keep
    their edges, which a low-pass would smooth."""
    from fwid.diagnosis._signals import commanded

    dt = 1 / 300
    t = np.arange(int(5 / dt)) * dt
    f = 12.0 + 0.5 * np.sin(2 * np.pi * 0.2 * t)
    phase = np.concatenate([[0.0], np.cumsum(np.pi * dt * (f[1:] + f[:-1]))])
    steps = 0.1 * np.select([(t > 1) & (t < 1.6), (t >= 1.6) & (t < 2.0)], [1.0, -1.0], 0.0)
    ripple = 0.03 * np.sin(phase + 0.4) + 0.01 * np.cos(2 * phase) + 0.004 * np.sin(3 * phase)
    got = commanded(steps + ripple, phase)
    np.testing.assert_allclose(got - np.mean(got), steps - np.mean(steps), atol=2e-3)
    edge = int(round(1.6 / dt))  # the step down at 1.6 s, in one sample
    assert got[edge + 1] - got[edge - 1] < -0.19


def test_a_rate_limited_servo_acts_on_the_command_not_on_the_ripple():
    """A load driven by a rate-limited servo on a doublet's steps, the measured elevator
    rippling at the wing beat (not commanded: the servo never sees it). The column
    (the servo on the deflection as commanded) reproduces the load's cycle-averaged part;
    the servo fed the ripple as well binds on every wing beat and does not."""
    from fwid.decomposition import decompose
    from fwid.diagnosis._catalogue.actuator_dynamics import _columns, actuator_filter

    dt = 1 / 300
    t = np.arange(int(6 / dt)) * dt
    cmd = 0.25 * np.select([(t > 1) & (t < 1.5), (t >= 1.5) & (t < 2.0)], [1.0, -1.0], 0.0)
    servo = ("rate-limit", 0.03, 3.0)
    load = 3.0 * actuator_filter(cmd, dt, servo)
    d = cmd + 0.06 * np.sin(2 * np.pi * 12.5 * t - 0.7)  # ripple rate 4.7 rad/s > 3
    parts = decompose({"de": d, "M": load}, dt)
    base = _signals(np.asarray(parts.averaged["de"]), np.asarray(parts.flapping["de"]), dt)
    averaged = np.asarray(parts.averaged["M"])
    inside = slice(int(0.5 / dt), -int(0.5 / dt))

    def misfit(col):
        k = np.dot(col[inside], averaged[inside]) / np.dot(col[inside], col[inside])
        return np.std(k * col[inside] - averaged[inside]) / np.std(averaged[inside])

    rippled = decompose({"x": actuator_filter(d, dt, servo)}, dt).averaged["x"]
    new, old = misfit(_columns(base, "M", servo, None, None)[:, 0]), misfit(np.asarray(rippled))
    assert new < 0.03 and old > 2 * new  # 1.6 % against 4.1 %


def test_a_nonlinear_servo_acts_on_the_measured_deflection_before_the_split():
    """A load driven by a direction-dependent servo on a 3211's steps: the column (the servo
    on the deflection as measured, then split as the loads are) reproduces the load's
    cycle-averaged part; the servo on the already smoothed cycle-averaged deflection does
    not, since a nonlinear filter does not commute with the split."""
    from fwid.decomposition import decompose
    from fwid.diagnosis._catalogue.actuator_dynamics import _columns, actuator_filter

    dt = 1 / 300
    t = np.arange(int(6 / dt)) * dt
    d = 0.1 * np.select([(t > 1) & (t < 1.6), (t >= 1.6) & (t < 2.0), (t >= 2.0) & (t < 2.2),
                         (t >= 2.2) & (t < 2.4)], [1.0, -1.0, 1.0, -1.0], 0.0)
    servo = ("asymmetric", 0.02, 0.1)
    load = 3.0 * actuator_filter(d, dt, servo)
    parts = decompose({"de": d, "M": load}, dt)
    base = _signals(np.asarray(parts.averaged["de"]), np.asarray(parts.flapping["de"]), dt)
    averaged = np.asarray(parts.averaged["M"])
    inside = slice(int(0.5 / dt), -int(0.5 / dt))

    def misfit(col):
        return np.std(3.0 * col[inside] - averaged[inside]) / np.std(averaged[inside])

    new, old = misfit(_columns(base, "M", servo, None, None)[:, 0]), misfit(
        actuator_filter(base.slow["de"], dt, servo))
    assert new < 0.02 and old > 4 * new  # 1.0 % against 5.9 %


def test_a_lagged_saturating_servo_is_named_alone(tmp_path):
    # The simulator's rudder saturates smoothly behind a 0.03 s lag. With the nonlinear
    # members' lags on two values (0.02, 0.05 s), the lag the nearest member left over was
    # taken up by `unsteady-aero` beside it; with the chosen member's lag refined on the
    # first-order members' grid the servo is named alone.
    import fwid
    from fwid.synth import write_flights

    kw = dict(effect="actuator-dynamics", form="saturation", noise=1.0, duration=5.0, rate=200.0)
    write_flights(tmp_path / "fit", 6, "lat", seed=0, **kw)
    write_flights(tmp_path / "test", 6, "lat", seed=500, **kw)
    d = fwid.diagnose(fwid.load_flights(tmp_path / "fit"), fwid.load_flights(tmp_path / "test"),
                      axis="lat", simulation=False, process_noise=False)
    assert d.verdict == "actuator-dynamics"
    assert [x["explanation"] for x in d.confidence_set] == [["actuator-dynamics"]]
    assert "tau = 0.03 s" in d.effects[0]["variant"]


def test_refine_moves_only_the_lag_of_a_nonlinear_or_rate_limited_member():
    from fwid.diagnosis._catalogue.actuator_dynamics import REFINED_LAGS, refine

    near = refine(("saturation", 0.02, 0.2, "before"))
    assert [v[1] for v in near] == list(REFINED_LAGS)
    assert all(v[0] == "saturation" and v[2:] == (0.2, "before") for v in near)
    assert [v[2] for v in refine(("rate-limit", 0.05, 3.0))] == [3.0] * len(REFINED_LAGS)
    assert refine(("lag", 0.05)) == () and refine(("second-order", 8.0, 0.5)) == ()


def test_every_member_s_acting_deflection_at_once_is_each_one_s():
    from fwid.diagnosis._catalogue.actuator_dynamics import acting, acting_all

    x = np.cumsum(np.random.default_rng(0).standard_normal(600)) * 0.01
    every = acting_all(x, 0.005, 5.0, ACTUATOR_FILTERS)
    assert every.shape == (600, len(ACTUATOR_FILTERS))
    for k, v in enumerate(ACTUATOR_FILTERS):
        np.testing.assert_allclose(every[:, k], acting(x, 0.005, 5.0, v), atol=1e-12)
