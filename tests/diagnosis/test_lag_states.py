"""`unsteady-aero`'s augmented model with its lags as states: the same model as the one fed
the lagging part of its states as inputs, and what lets a discriminating design drive it."""

import numpy as np
import pytest

import fwid
from fwid.design._signals import Grid, input_3211
from fwid.diagnosis._augment import augment
from fwid.diagnosis._catalogue.unsteady_aero import Lagging, lagging, unsteady_states
from fwid.diagnosis._lag_states import lag_states

TAU = 0.1
LAG = {"X_lag": 0.8, "Z_lag": 0.8, "M_lag": 0.8}


@pytest.fixture(scope="module")
def setup():
    from fwid.synth import DELFLY, NOISE

    vehicle, trim = DELFLY.vehicle(), DELFLY.trim()
    consts = {"mass": vehicle["mass"], "Iy": vehicle["Iy"], "g": vehicle["g"],
              "u0": trim["u0"], "w0": trim["w0"], "theta0": trim["theta0"]}
    R = np.diag([NOISE[k] ** 2 for k in ("q", "u", "w", "theta")])
    base = fwid.longitudinal()
    member = Lagging("lag", TAU, {ld: {x: float(base.params[f"{ld}{x}"])
                                       for x in unsteady_states(ld)} for ld in "XZM"})
    model, _, _ = augment("lon", [("unsteady-aero", member)])
    return model.with_params(LAG), model, consts, R, member


def _lagp(model, member, y, dt):
    """`lagging` (the diagnosis's filter, numpy) of each load's quasi-steady load along the
    outputs `y`."""
    return np.stack([lagging(sum(g * y[:, model.states.index(x)]
                                 for x, g in member.derivatives[ld].items()), dt, member)
                     for ld in "XZM"], axis=1)


def _simulate(model, t, u, consts):
    exp = fwid.Experiment(t, u, np.zeros((t.size, len(model.outputs))),
                          x0=np.zeros(len(model.states)), consts=consts)
    xs, ys = fwid.simulate(model, exp)
    return np.asarray(xs), np.asarray(ys)


def _against_inputs(model, inner, member, consts, rate):
    """The lag-state model `inner` flown on a 3211 at `rate` (Hz), and the input-lag `model`
    fed the lagging quasi-steady loads (the filter the diagnosis prepares the inputs with)
    of the outputs `inner` simulated, and fed none: `(xs, ys, lagp, y_in, y_held, scale)`,
    `scale` each output's peak."""
    grid = Grid(4.0, 1.0, rate)
    t, de = grid.t, input_3211(grid, 0.12)
    xs, ys = _simulate(inner, t, de[:, None], consts)
    lagp = _lagp(model, member, ys, t[1] - t[0])
    _, y_in = _simulate(model, t, np.column_stack([de, lagp]), consts)
    _, y_held = _simulate(model, t, np.column_stack([de, 0 * lagp]), consts)
    return xs, ys, lagp, y_in, y_held, np.max(np.abs(ys), axis=0)


def test_the_lag_states_equal_the_lag_inputs_fed_the_models_own_states(setup):
    model, _, consts, _, member = setup
    inner = lag_states(model, "lon", member)
    assert inner.states == ("q", "u", "w", "theta", "X_lag1", "Z_lag1", "M_lag1")
    assert inner.inputs == ("de",) and inner.outputs == model.outputs
    # the input-lag model, fed the lagging quasi-steady loads of the states the lag-state
    # model simulated, simulates them back
    xs, ys, lagp, y_in, y_held, scale = _against_inputs(model, inner, member, consts, 100.0)
    assert np.all(np.max(np.abs(ys - y_in), axis=0) < 2e-3 * scale)
    # the lag states are the lagged quasi-steady loads (z = qs + lag(qs) - qs)
    qs = np.stack([sum(g * xs[:, model.states.index(x)] for x, g in member.derivatives[ld].items())
                   for ld in "XZM"], axis=1)
    np.testing.assert_allclose(xs[:, 4:], qs + lagp, atol=1e-2 * np.max(np.abs(qs)))
    # ... and the terms matter: held at zero, the prediction is another one
    assert np.all(np.max(np.abs(ys - y_held), axis=0) > 0.2 * scale)


def test_a_discriminating_design_drives_the_lag_terms(setup):
    model, plain, consts, R, member = setup
    zero = {k: 0.0 for k in LAG}
    # two models that differ only in the lag terms: with the lags held at zero (the inputs of
    # the augmented model) no input tells them apart
    t = np.linspace(0.0, 3.0, 61)
    de = 0.1 * np.sign(np.sin(2 * np.pi * 0.7 * t))[:, None]
    held = np.column_stack([de, np.zeros((t.size, 3))])
    np.testing.assert_array_equal(_simulate(model, t, held, consts)[1],
                                  _simulate(plain.with_params(zero), t, held, consts)[1])
    a, b = lag_states(plain.with_params(zero), "lon", member), lag_states(model, "lon", member)
    d = fwid.design_discriminating(a, b, consts=consts, R=R, amplitude=0.1, duration=3.0,
                                   quiet=1.0, rate=20.0, attitude="theta", restarts=2,
                                   iterations=30, switch_rate=5.0)
    ya = _simulate(a, d.t, d.u[:, None], consts)[1]
    yb = _simulate(b, d.t, d.u[:, None], consts)[1]
    W = np.linalg.inv(R)
    assert d.distance == pytest.approx(np.einsum("ki,ij,kj->", ya - yb, W, ya - yb), rel=1e-9)
    assert d.distance > 10.0  # many noise variances: a flight would tell them apart
    assert d.distance >= d.distance_3211 > 0


def test_the_loads_along_a_trajectory_are_the_input_lag_models_loads(setup):
    # `states_along` + the lag-state model's force model = the input-lag model's force model
    # fed `lagging` of the trajectory (numpy, the diagnosis's filter): what the loads
    # criterion of the discriminating design compares
    from fwid.diagnosis._lag_states import states_along
    from fwid.simulation._simulate import simulate_forces

    model, _, consts, _, member = setup
    inner = lag_states(model, "lon", member)
    t = np.linspace(0.0, 3.0, 151)
    de = 0.1 * np.sign(np.sin(2 * np.pi * 0.7 * t))
    y = _simulate(inner, t, de[:, None], consts)[1] + 0.01 * np.sin(7 * t)[:, None]
    x = np.asarray(states_along(inner, y, t[1] - t[0]))
    assert x.shape == (t.size, 7)
    z4 = np.zeros((t.size, 4))
    got = np.asarray(simulate_forces(inner, x, fwid.Experiment(t, de[:, None], z4,
                                                               x0=np.zeros(7), consts=consts)))
    lagp = _lagp(model, member, y, t[1] - t[0])

    def loads(lag_inputs):
        exp = fwid.Experiment(t, np.column_stack([de, lag_inputs]), z4, x0=np.zeros(4),
                              consts=consts)
        return np.asarray(simulate_forces(model, y, exp))
    want = loads(lagp)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * np.max(np.abs(want)))
    assert np.max(np.abs(want - loads(0 * lagp))) > 1e-3 * np.max(np.abs(want))


def test_a_delay_takes_its_pade_form(setup):
    """A delay has no finite state: its first-order Pade form simulates the outputs the
    input-lag model gives fed the delayed quasi-steady loads of those outputs, within 2 %
    (an all-pass approximant, not the delay)."""
    model, _, consts, _, lag = setup
    member = Lagging("delay", 0.05, lag.derivatives)
    inner = lag_states(model, "lon", member)
    assert inner.states[4:] == ("X_lag1", "Z_lag1", "M_lag1")
    _, ys, _, y_in, y_held, scale = _against_inputs(model, inner, member, consts, 200.0)
    err = np.max(np.abs(ys - y_in), axis=0) / scale
    assert np.all(err < 0.02), err
    assert np.all(np.max(np.abs(ys - y_held), axis=0) > 5 * err * scale)
