"""The identified model leaves fwid as A, B, C, D: round trips through scipy and
python-control give fwid's eigenvalues and fwid's simulated step response."""

import jax.numpy as jnp
import numpy as np
import pytest
from scipy import signal

import fwid
from fwid.models import TABLE1, longitudinal

CONSTS = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
DT, N = 0.005, 601


def _model():
    return longitudinal(TABLE1)  # biases are zero: the model is exactly linear


def test_eigenvalues_round_trip():
    ss = fwid.state_space(_model(), CONSTS)
    assert ss.states == ("q", "u", "w", "theta") and ss.inputs == ("de",)
    np.testing.assert_allclose(np.sort_complex(ss.poles()),
                               np.sort_complex(fwid.eigenvalues(_model(), CONSTS)), rtol=1e-10)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(ss.to_scipy().A)),
                               np.sort_complex(ss.poles()), rtol=1e-12)
    np.testing.assert_array_equal(ss.C, np.eye(4))
    np.testing.assert_array_equal(ss.D, np.zeros((4, 1)))


def test_step_response_round_trip():
    """scipy's lsim of the exported system (first-order hold, exact for a linear system)
    against fwid's diffrax RK4 simulation of the model: the same response."""
    model = _model()
    t = np.arange(N) * DT
    u = np.where(t > 0.1, 0.05, 0.0)[:, None]
    exp = fwid.Experiment(t, u, np.zeros((N, 4)), x0=np.zeros(4), consts=CONSTS)
    _, y_fwid = fwid.simulate(model, exp)
    _, y_scipy, _ = signal.lsim(fwid.state_space(model, CONSTS).to_scipy(), u[:, 0], t)
    scale = np.max(np.abs(y_scipy), axis=0)
    np.testing.assert_allclose(np.asarray(y_fwid) / scale, y_scipy / scale, atol=1e-6)


def test_to_control_names():
    control = pytest.importorskip("control")
    sys = fwid.state_space(_model(), CONSTS).to_control()
    assert isinstance(sys, control.StateSpace)
    assert sys.state_labels == ["q", "u", "w", "theta"] and sys.input_labels == ["de"]
    np.testing.assert_allclose(np.sort_complex(control.poles(sys)),
                               np.sort_complex(fwid.eigenvalues(_model(), CONSTS)), rtol=1e-10)


def test_output_equation_is_linearised():
    """A user model with an output equation `h`: C = dh/dx, D = dh/du."""

    def f(x, u, p, c):
        return jnp.stack([x[1], -p["k"] * x[0] - 0.5 * x[1] + u[0]])

    def h(x, u, p, c):
        return jnp.stack([x[0], c["g"] * x[1] + 2.0 * u[0]])

    m = fwid.GreyBoxModel(f, states=("a", "b"), inputs=("u",), params=dict(k=4.0),
                          h=h, outputs=("a", "acc"), constants=("g",))
    ss = fwid.state_space(m, dict(g=3.0))
    np.testing.assert_allclose(ss.A, [[0, 1], [-4, -0.5]])
    np.testing.assert_allclose(ss.C, [[1, 0], [0, 3]])
    np.testing.assert_allclose(ss.D, [[0], [2]])
    assert ss.outputs == ("a", "acc") and "poles" in repr(ss)


def test_from_json_restores_the_system_without_fitting():
    """`report.json["state_space"]` back into a `StateSpace`: the same matrices and names."""
    import json

    ss = fwid.StateSpace(np.array([[-1.0, 2.0], [0.0, -3.0]]), np.array([[1.0], [0.5]]),
                         np.eye(2), np.zeros((2, 1)), ("q", "w"), ("de",), ("q", "w"))
    back = fwid.StateSpace.from_json(json.loads(json.dumps(ss.to_json())))
    for k in "ABCD":
        np.testing.assert_array_equal(getattr(back, k), getattr(ss, k))
    assert (back.states, back.inputs, back.outputs) == (ss.states, ss.inputs, ss.outputs)
