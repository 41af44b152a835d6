"""Least-squares (equation-error) start values, Sec. IV.B."""

import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.estimate import least_squares_start
from fwid.models import lateral, longitudinal


def _smooth(t, amp=0.05):
    env = np.sin(np.pi * t / t[-1])
    return amp * env * (np.sin(2 * np.pi * 0.8 * t) + 0.6 * np.sin(2 * np.pi * 2.1 * t + 0.5))


def _family(flight):
    return longitudinal if flight.model.name == "lon" else lateral


def _split(flight):
    aero = np.array([k not in flight.model.local for k in flight.names])
    return aero, ~aero


@pytest.fixture(scope="module", params=["lon", "lat"])
def flight(request, lon_flight, lat_flight):
    return lon_flight if request.param == "lon" else lat_flight


def test_with_forces_returns_true_force_parameters(flight):
    start = least_squares_start(_family(flight)(), [flight.experiment(forces=True)])
    theta = np.asarray(start.theta())
    aero, bias = _split(flight)
    np.testing.assert_allclose(theta[aero], flight.theta[aero], rtol=1e-8, atol=0)
    # the biases (not in the force model) come from the state-derivative regression
    np.testing.assert_allclose(theta[bias], flight.theta[bias], rtol=0, atol=1e-4)


def test_start_does_not_depend_on_the_model_values(lon_flight):
    exp = lon_flight.experiment()
    a = least_squares_start(longitudinal(), [exp])
    true = {k: float(v) for k, v in lon_flight.model.params.items()}
    far = longitudinal({k: -3.0 * v for k, v in true.items()})
    b = least_squares_start(far, [exp])
    np.testing.assert_allclose(np.asarray(b.theta()), np.asarray(a.theta()), rtol=1e-9,
                               atol=1e-12)
    # fixed (non-free) parameters are left alone
    fixed = longitudinal().with_free([k for k in true if k != "Mq"]).with_params(Mq=-7e-4)
    c = least_squares_start(fixed, [exp])
    assert float(c.params["Mq"]) == -7e-4
    assert "Mq" not in c.free


def test_without_forces_state_regression_is_close_on_3211(lon_flight):
    start = least_squares_start(longitudinal(), [lon_flight.experiment()])
    theta = np.asarray(start.theta())
    aero, bias = _split(lon_flight)
    # numerical differentiation across the 3211's steps costs a few percent
    rel = np.abs(theta[aero] / lon_flight.theta[aero] - 1)
    assert np.all(rel < 0.1), dict(zip(np.array(lon_flight.names)[aero], rel.round(3)))
    A, B = start.state_matrices(start.params, lon_flight.consts)
    A0, B0 = lon_flight.model.state_matrices(lon_flight.model.params, lon_flight.consts)
    assert np.linalg.norm(A - A0) < 0.05 * np.linalg.norm(A0)
    assert np.linalg.norm(B - B0) < 0.05 * np.linalg.norm(B0)


@pytest.mark.parametrize("which", ["lon", "lat"])
def test_without_forces_state_regression_close_on_smooth_input(which, lon_flight,
                                                                flight_factory):
    t = lon_flight.t
    fl = flight_factory(which, _smooth(t, amp=0.05 if which == "lon" else 0.1))
    start = least_squares_start(_family(fl)(), [fl.experiment()])
    rel = np.abs(np.asarray(start.theta()) / fl.theta - 1)
    assert np.all(rel < 0.05), dict(zip(fl.names, rel.round(4)))
    assert np.median(rel) < 0.005, rel
    A, B = start.state_matrices(start.params, fl.consts)
    A0, B0 = fl.model.state_matrices(fl.model.params, fl.consts)
    assert np.linalg.norm(A - A0) < 0.01 * np.linalg.norm(A0)
    assert np.linalg.norm(B - B0) < 0.01 * np.linalg.norm(B0)
