"""An ambiguous diagnosis designs its next flight (`next_flight.csv`), and `fwid design
--discriminate` on its folder designs the same input again.

The two augmented models' re-fit (`discriminating_models`, output error on the training
flights: minutes) is replaced by two small models that differ in the control's lag, what
actuator-dynamics and time-offset differ in; the design, the files and the settings read back
are the real ones."""

import json

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.cli import main
from fwid.cli import _discriminate as disc
from fwid.synth import write_flights


def _models(axis, pair, flights, say=None):
    def lagged(tau):
        def f(x, u, p, c):
            return jnp.stack([-2.0 * x[0] + x[1], (u[0] - x[1]) / p["tau"]])
        return fwid.GreyBoxModel(f, states=("q", "s"), inputs=("de",), params={"tau": tau})

    models = [lagged(0.03), lagged(0.12)]
    maps = [disc.control_map(m, axis, None) for m in models]
    return models, maps, [], {}, np.diag([1e-4, 1e-4])


@pytest.fixture(scope="module")
def ambiguous(tmp_path_factory):
    root = tmp_path_factory.mktemp("next")
    paths = write_flights(root / "train", 2, "lon", seed=5, duration=2.0)
    for p in paths:
        p.with_suffix(".json").unlink(missing_ok=True)
    diag = {"verdict": "actuator-dynamics", "axis": "lon", "train": [p.name for p in paths],
            "candidates": [{"effect": "actuator-dynamics",
                            "variant": "first-order lag, tau = 0.04 s"},
                           {"effect": "time-offset", "variant": "0.03 s"}],
            "confidence_set": [{"explanation": ["actuator-dynamics"], "gain_pct": 6.0},
                               {"explanation": ["time-offset"], "gain_pct": 5.8}],
            "method": {"train_paths": [str(p) for p in paths]}}
    return root, paths, diag


def test_the_next_flight_is_written_and_design_discriminate_designs_it_again(
        ambiguous, monkeypatch, capsys):
    root, paths, diag = ambiguous
    monkeypatch.setattr(disc, "discriminating_models", _models)
    flights = fwid.load_flights(str(root / "train"))
    out = root / "diag"
    rec = disc.next_flight_input(diag, flights, out, restarts=2, duration=3.0, by="outputs")
    assert rec["input"] == "next_flight.csv" and rec["control"] == "de"
    amp = disc.flown_amplitude(flights, "lon")
    assert amp == pytest.approx(np.median([np.ptp(np.asarray(f["de"])) / 2 for f in flights]))
    assert rec["design"]["amplitude"] == pytest.approx(amp) and amp > 0
    got = np.loadtxt(out / "next_flight.csv", delimiter=",", skiprows=1)
    assert (out / "next_flight.csv").read_text().splitlines()[0] == "t,de"
    # 3 s at 100 Hz, silent for the first second, within the amplitude flown
    assert got.shape == (rec["samples"], 2) and rec["samples"] == round(3.0 * disc.NEXT_FLIGHT["rate"]) + 1
    assert np.all(got[got[:, 0] <= 1.0, 1] == 0.0)
    assert 0.5 * amp < np.max(np.abs(got[:, 1])) <= amp + 1e-9
    assert rec["criterion"]["designed"] >= max(
        v for v in rec["criterion"]["alternatives"].values() if v is not None) - 1e-9
    # diagnosis.json records it; `fwid design --discriminate DIR` without --amplitude designs
    # it again from the recorded settings
    (out / "diagnosis.json").write_text(json.dumps(
        {**diag, "next_flight": {"tell_apart": ["actuator-dynamics", "time-offset"], **rec}}))
    assert main(["design", "--discriminate", str(out), "--out", str(root / "again"),
                 "--no-progress"]) == 0
    again = np.loadtxt(root / "again" / "input.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(again, got, atol=1e-9)
    capsys.readouterr()
    # without a designed next flight, --amplitude is needed: one line naming it
    (out / "diagnosis.json").write_text(json.dumps(diag))
    assert main(["design", "--discriminate", str(out), "--out", str(root / "x")]) == 2
    assert "--amplitude" in capsys.readouterr().err
    failed = {"tell_apart": ["actuator-dynamics", "time-offset"], "failed": "InputError: why"}
    (out / "diagnosis.json").write_text(json.dumps({**diag, "next_flight": failed}))
    assert main(["design", "--discriminate", str(out), "--out", str(root / "x")]) == 2
    err = capsys.readouterr().err
    assert "its design failed: InputError: why" in err and len(err.strip().splitlines()) == 1


def test_the_summary_names_the_pair_and_the_file():
    from types import SimpleNamespace

    from fwid.report._diagnosis import confidence_set_line

    nxt = {"tell_apart": ["actuator-dynamics", "nonlinear-aero"], "input": "next_flight.csv",
           "criterion": {"designed": 12.5, "ratio": 1.8}}
    d = SimpleNamespace(confidence_set=[{"explanation": ["actuator-dynamics"], "gain_pct": 5.0,
                                         "p_value": 1.0},
                                        {"explanation": ["nonlinear-aero"], "gain_pct": 4.6,
                                         "p_value": 0.4}],
                        settings={"confidence_level": 0.1}, next_flight=nxt)
    line = confidence_set_line(d)
    assert ("ambiguous between actuator-dynamics and nonlinear-aero: fly next_flight.csv next"
            in line) and "1.80x a 3211's" in line
    failed = SimpleNamespace(**{**vars(d), "next_flight": {"tell_apart": nxt["tell_apart"],
                                                           "failed": "InputError: diverges"}})
    assert "not designed here: InputError: diverges" in confidence_set_line(failed)
