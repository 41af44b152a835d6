"""A `report.json` of the longitudinal model at the paper's values (Table 1), written without a
fit: the design reads its parameters, trim and vehicle, and `fit.R`."""

import json

import numpy as np
import pytest


def lon_report() -> dict:
    from fwid.models._delfly import TABLE1
    from fwid.synth import DELFLY, NOISE

    vehicle, trim = DELFLY.vehicle(), DELFLY.trim()
    consts = {"mass": vehicle["mass"], "Iy": vehicle["Iy"], "g": vehicle["g"],
              "u0": trim["u0"], "w0": trim["w0"], "theta0": trim["theta0"]}
    R = np.diag([NOISE[k] ** 2 for k in ("q", "u", "w", "theta")])
    return {"model": "lon", "flights": ["lon_0.csv"],
            "parameters": {k: {"value": v, "std": abs(v) / 100} for k, v in TABLE1.items()},
            "trim_and_vehicle": consts,
            "fit": {"R": R.tolist(), "outputs": ["q", "u", "w", "theta"]},
            "metrics": {"estimation": {}}}


@pytest.fixture(scope="session")
def report_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("design") / "report.json"
    path.write_text(json.dumps(lon_report()))
    return path
