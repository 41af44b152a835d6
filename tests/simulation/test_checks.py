"""An Experiment is what it claims: uniform time, shapes that match the model, an x0."""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid

T = np.arange(200) * 0.01


def _model(h=None, outputs=None):
    def f(x, u, p, c):
        return jnp.stack([p["a"] * x[0] + p["b"] * u[0], x[0] - x[1]])

    return fwid.GreyBoxModel(f, states=("x1", "x2"), inputs=("u",), params=dict(a=-1.0, b=1.0),
                             h=h, outputs=outputs, name="toy")


def _u():
    return np.sin(3 * T)


def test_gap_in_time_axis_names_index_steps_and_fix():
    t = T.copy()
    t[120:] += 10.0  # a 10 s gap
    with pytest.raises(fwid.FlightDataError) as info:
        fwid.Experiment(t, _u(), np.zeros((200, 2)))
    msg = str(info.value)
    assert "index 120" in msg
    assert "10.01 s" in msg and "0.01 s was expected" in msg
    assert "Split the record into experiments" in msg


def test_one_longer_step_is_rejected():
    t = T.copy()
    t[50:] += 0.005  # one step of 1.5 dt
    with pytest.raises(fwid.FlightDataError, match=r"index 50 .*step is 0.015 s"):
        fwid.Experiment(t, _u(), np.zeros((200, 2)))


def test_fit_rejects_an_experiment_with_a_gap_built_without_checks():
    e = fwid.Experiment(T, _u(), np.zeros((200, 2)))
    t = T.copy()
    t[30:] += 1.0
    bad = fwid.Experiment.__new__(fwid.Experiment)
    for k, v in vars(e).items():
        object.__setattr__(bad, k, jnp.asarray(t) if k == "t" else v)
    with pytest.raises(fwid.FlightDataError, match="flightA: the time axis is not uniform: at index 30"):
        fwid.fit(_model(), [bad], names=["flightA"], start="model")


def test_lengths_of_u_and_z_are_checked():
    with pytest.raises(fwid.InputError, match=r"u \(inputs\) has shape \(199, 1\) but t has 200"):
        fwid.Experiment(T, np.zeros(199), np.zeros((200, 2)))
    with pytest.raises(fwid.InputError, match=r"z \(measured outputs\) has shape \(150, 2\)"):
        fwid.Experiment(T, np.zeros(200), np.zeros((150, 2)))


def test_shapes_against_the_model_name_each_channel():
    m = _model()
    with pytest.raises(fwid.InputError, match=r"u has 2 column\(s\) but the toy model has 1 input\(s\) \(u\)"):
        fwid.fit(m, fwid.Experiment(T, np.zeros((200, 2)), np.zeros((200, 2))), start="model")
    with pytest.raises(fwid.InputError, match=r"z has 3 column\(s\) .* 2 output\(s\) \(x1, x2\)"):
        fwid.fit(m, fwid.Experiment(T, _u(), np.zeros((200, 3)), x0=np.zeros(2)), start="model")
    with pytest.raises(fwid.InputError, match=r"x0 has shape \(3,\) .* 2 state\(s\) \(x1, x2\)"):
        fwid.fit(m, fwid.Experiment(T, _u(), np.zeros((200, 2)), x0=np.zeros(3)), start="model")


def test_missing_x0_when_outputs_are_not_states_says_how_to_pass_it():
    m = _model(h=lambda x, u, p, c: x[:1] + x[1:], outputs=("y",))
    with pytest.raises(fwid.InputError) as info:
        fwid.fit(m, fwid.Experiment(T, _u(), np.zeros((200, 1))), start="model")
    msg = str(info.value)
    assert "no x0 was given" in msg and "are not its states (x1, x2)" in msg
    assert "x0=[x1, x2]" in msg


def test_a_uniform_experiment_still_fits():
    m = _model()
    _, ys = fwid.simulate(m.with_params(a=-2.0), fwid.Experiment(T, _u(), np.zeros((200, 2)),
                                                                 x0=np.zeros(2)))
    r = fwid.fit(m, fwid.Experiment(T, _u(), np.asarray(ys), x0=np.zeros(2)), start="model")
    assert abs(float(r.params["a"]) + 2.0) < 1e-6
