"""A diagnosis never throws its run away: an optional block that fails is recorded and the
rest is written; a bias term the flights cannot identify is held and named."""

import json
from concurrent.futures import Future

import numpy as np
import pytest

import fwid
from fwid.diagnosis import _diagnose, _simulation


class _FailingFits:
    """`EarlyFits` whose baseline fit ended in `error` (as the output-error fit of a flight
    without excitation ends)."""

    def __init__(self, error):
        self.baseline = Future()
        self.baseline.set_exception(error)

    def __call__(self, *args, **kwargs):
        return self

    def start(self, effects):
        pass

    def get(self, effects):
        return None

    def close(self):
        pass


@pytest.mark.parametrize("error", [
    fwid.ExcitationError("lon_1.csv: the data carry no information on parameters Xde, bw "
                         "(too little excitation)", parameters=("Xde", "bw")),
    fwid.FitDivergedError("lon_0.csv: the lon fit diverged"),
])
def test_a_failed_simulation_block_is_recorded_and_the_rest_written(effect_flights, tmp_path,
                                                                    monkeypatch, error):
    """The simulation block raising (an unidentifiable parameter, a diverged fit) leaves the
    verdict, the candidates and the gap map standing: `simulation.failed` says why, a
    `DiagnosisWarning` too, and `write_diagnosis` writes diagnosis.json and the gap map."""
    from fwid.report import diagnosis_summary, write_diagnosis

    train, test = (fwid.load_flights(p) for p in effect_flights(
        "actuator-dynamics", strength=1.0, seed=6, n_train=2, n_test=2))
    monkeypatch.setattr(_diagnose, "EarlyFits", _FailingFits(error))
    with pytest.warns(fwid.DiagnosisWarning, match="simulation block failed"):
        d = fwid.diagnose(train, test, process_noise=False)
    assert d.models is None
    assert d.simulation["failed"].startswith(type(error).__name__ + ": ")
    assert str(error).split(":")[0] in d.simulation["failed"]
    assert "\n" not in d.simulation["failed"]
    written = write_diagnosis(d, tmp_path)
    assert written == ["diagnosis.json", "gap_map.png"]
    out = json.loads((tmp_path / "diagnosis.json").read_text())
    assert out["verdict"] == d.verdict and out["candidates"] and out["localisation"]
    assert out["simulation"]["failed"] == d.simulation["failed"]
    assert "in simulation: not measured: the block failed" in diagnosis_summary(d)


def _bq_unidentified_once(monkeypatch):
    """`identify` as the diagnosis's fits call it, except that its first joint fit reports
    flight 1's `bq` as carrying no information (as `check_information` does): the calls made
    are in the list returned."""
    real, calls = _simulation.identify, []

    def identify(flights, model, **kw):
        calls.append(kw.get("prior"))
        out = real(flights, model, **kw)
        if len(calls) == 1:
            raise fwid.ExcitationError("no information on bq@1", parameters=("bq@1",))
        return out

    monkeypatch.setattr(_simulation, "identify", identify)
    return calls


def test_an_unidentified_bias_is_held_at_its_start_and_named(effect_flights, monkeypatch):
    """A joint fit whose second flight's `bq` the flights cannot identify goes on: `bq@1` is
    held at the baseline's equation-error start value and named (`pinned`, the simulation
    block's `fixed_bias_terms` and a warning); flight 0's copy stays free."""
    from fwid.estimate import least_squares_start
    from fwid.simulation import averaged

    train, test = (fwid.load_flights(p) for p in effect_flights(
        "actuator-dynamics", strength=1.0, seed=6, n_train=2, n_test=2))
    calls = _bq_unidentified_once(monkeypatch)
    ident = _simulation.fit_baseline(train, test, "lon")
    model = _simulation.get_model("lon")
    start = least_squares_start(model, [averaged(f, model, 5.0) for f in train])
    bq0 = float(start.params["bq"])
    assert len(calls) == 2 and calls[0] is None and list(calls[1]) == ["bq@1"]
    assert ident.pinned == {"bq@1": bq0}
    fit = ident.fits[0]
    theta = dict(zip(fit.names, np.asarray(fit.theta)))
    assert theta["bq@1"] == pytest.approx(bq0, rel=1e-6, abs=1e-9)
    assert abs(theta["bq@0"] - bq0) > 1e-6  # the other flight's copy was fitted
    # the block names it, in its data and as a warning
    with pytest.warns(fwid.DiagnosisWarning, match="bq@1"):
        block = _simulation.simulation_gap(train, test, "lon", [], baseline=ident).summary
    assert block["fixed_bias_terms"] == {"baseline": {"bq@1": bq0}, "augmented": {}}
    assert any("bq@1" in w and "equation-error start" in w for w in block["warnings"])


def test_an_unidentified_shared_parameter_is_not_held(monkeypatch):
    """Only bias terms are held: a parameter every flight shares (`Xde`) that the flights do
    not identify is raised, for the block to record."""
    def identify(flights, model, **kw):
        raise fwid.ExcitationError("no information on Xde, bq@1", parameters=("Xde", "bq@1"))

    monkeypatch.setattr(_simulation, "identify", identify)
    with pytest.raises(fwid.ExcitationError, match="Xde"):
        _simulation.identify_pinned([object(), object()], [], _simulation.get_model("lon"), 5.0)
    assert _simulation._bias_terms(["bq@1", "bw@0"], _simulation.get_model("lon"), 2)
    assert not _simulation._bias_terms(["bq"], _simulation.get_model("lon"), 2)
    assert _simulation._bias_terms(["bw"], _simulation.get_model("lon"), 1)
