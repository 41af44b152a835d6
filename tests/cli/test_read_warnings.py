"""What reading the flights warns about (a time base resampled, no quiet start) is printed
once, as one line, and leads `report.json`'s `warnings`; tested without a fit."""

import json

import numpy as np

from fwid.cli import main
from fwid.cli import _identify

from ..data.helpers import lon_flight, write_flight


def test_read_warnings_in_report(tmp_path, capsys, monkeypatch):
    c = lon_flight(t_input=0.05)
    c["t"] = c["t"] + np.random.default_rng(0).uniform(-0.02, 0.02, c["t"].shape) * 0.005
    path = write_flight(tmp_path / "flights", cols=c)

    def no_fit(args, flights, validate):  # the fit's own report, with a warning of its own
        return {"warnings": ["a fit warning"], "parameters": {}}, [], lambda r: "summary"

    monkeypatch.setattr(_identify, "_cycle_averaged", no_fit)
    out = tmp_path / "out"
    assert main(["identify", str(path), "--model", "lon", "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    said = [ln for ln in err if ln.startswith("fwid: warning: ")]
    assert len(said) == 2 and len(err) == 2, err
    assert "jitter" in said[0] and "no quiet start" in said[1]
    warnings = json.loads((out / "report.json").read_text())["warnings"]
    assert warnings == [said[0][len("fwid: warning: "):], said[1][len("fwid: warning: "):],
                        "a fit warning"]
