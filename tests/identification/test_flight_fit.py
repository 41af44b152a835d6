"""Scoring a model on a flight (`evaluate`): a model that diverges there is named with it."""

import pytest

import fwid
from fwid import FitDivergedError
from fwid.identification import get_model
from fwid.identification._flight_fit import evaluate
from fwid.simulation._averaged import averaged


def test_refitting_the_biases_of_a_diverging_model_names_the_flight(tmp_path):
    fwid.synth.write_flights(tmp_path, 1, axis="lon", seed=3)
    flight = fwid.load_flights(tmp_path)[0]
    model = get_model("lon")
    exp = averaged(flight, model, 5.0, 40.0)
    evaluate(model, exp, flight.name)  # the paper's model: finite
    unstable = model.with_params({"Mq": 0.5})  # pitch damping of the wrong sign, large
    with pytest.raises(FitDivergedError, match=f"{flight.name}: the model's simulation"):
        evaluate(unstable, exp, flight.name)
