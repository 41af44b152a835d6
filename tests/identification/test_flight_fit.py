"""Scoring a model on a flight (`evaluate`): the biases of a held-out flight, and its fit."""

import numpy as np
import pytest

import fwid
from fwid.identification import get_model
from fwid.identification._flight_fit import evaluate
from fwid.simulation._averaged import averaged


def test_a_diverging_model_re_estimates_its_biases_by_equation_error(tmp_path):
    """A held-out flight's biases cannot come from a simulation that runs away: they come
    from the state equations at the measured states, and the flight is still scored."""
    from fwid.estimate._equation_error import equation_error_locals

    fwid.synth.write_flights(tmp_path, 1, axis="lon", seed=3)
    flight = fwid.load_flights(tmp_path)[0]
    model = get_model("lon")
    exp = averaged(flight, model, 5.0, 40.0)
    stable = evaluate(model, exp, flight.name)  # the paper's model: by its simulation
    assert stable.local_params != equation_error_locals(model, exp, flight.name)
    unstable = model.with_params({"Mq": 0.5})  # pitch damping of the wrong sign, large
    ff = evaluate(unstable, exp, flight.name)
    want = equation_error_locals(unstable, exp, flight.name)
    assert ff.local_params == pytest.approx(want, rel=1e-12)
    assert all(np.isfinite(v) for v in ff.local_params.values())
    assert ff.local_params != stable.local_params
