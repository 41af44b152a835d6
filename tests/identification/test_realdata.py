"""The real Flapper Drone flights (`../shared/realdata`, see its SOURCES.md) from the
recording to a model, as a user runs it: `fwid reconstruct --map` with its default options
(the airborne cut), then `fwid identify --method equation-error` and `--method filter-error`
on each flight. Skipped when the folder is absent."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

import fwid
from fwid.cli import main

ROOT = Path(__file__).resolve().parents[2]
REAL = ROOT.parent / "shared" / "realdata"
MAP = ROOT / "docs" / "guide" / "flapper.toml"
NAMES = ("fd_model_tuning_level_flight_1", "fd_model_tuning_wAlt_1")
VEHICLE = {"mass": 0.103, "Ix": 3.2e-4, "Iy": 4.9e-4, "Iz": 3.5e-4, "Ixz": 0.0, "g": 9.81}

pytestmark = pytest.mark.skipif(not (REAL / f"{NAMES[0]}.csv.gz").exists(),
                                reason=f"real recordings not found beside the repository ({REAL})")


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    root = tmp_path_factory.mktemp("real")
    (root / "raw").mkdir()
    for n in NAMES:
        (root / "raw" / f"{n}.csv.gz").symlink_to(REAL / f"{n}.csv.gz")
    (root / "raw" / "vehicle.json").write_text(json.dumps(VEHICLE))
    assert main(["reconstruct", str(root / "raw"), "--map", str(MAP), "--out",
                 str(root / "flights"), "--no-figures", "--quiet"]) == 0
    return root / "flights"


@pytest.fixture(scope="module")
def identified(flights, tmp_path_factory):
    """`fwid identify FLIGHT --model lon --method METHOD` on each flight and method: the
    exit code, `report.json` and what it printed (stdout and stderr)."""
    import contextlib
    import io

    out = {}
    for method in ("equation-error", "filter-error"):
        for name in NAMES:
            where = tmp_path_factory.mktemp(method)
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
                rc = main(["identify", str(flights / f"{name}.csv"), "--model", "lon",
                           "--method", method, "--out", str(where), "--figures", "none",
                           "--quiet"])
            out[method, name] = (rc, json.loads((where / "report.json").read_text()),
                                 printed.getvalue())
    return out


def _oscillatory_wn(report):
    return next(m["wn"] for m in report["modes"] if m["kind"] == "oscillatory")


@pytest.mark.parametrize("method", ["equation-error", "filter-error"])
def test_both_methods_converge_on_each_real_flight(identified, method):
    wn = []
    for name in NAMES:
        rc, report, printed = identified[method, name]
        assert rc == 0, printed[-2000:]
        assert report["fit"]["converged"] and report["method"] == method
        numbers = [abs(float(x)) for x in re.findall(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?",
                                                      printed)]
        assert max(numbers) < 1e6, max(numbers)  # bounded output
        wn.append(_oscillatory_wn(report))
    assert max(wn) / min(wn) < 1.25, wn  # the same vehicle's short oscillation


def test_equation_error_predicts_the_other_flights_loads_as_least_squares_does(flights,
                                                                              identified):
    """Fitted on one flight, the equation-error model predicts the other's cycle-averaged
    loads (X, Z, M at its measured states, its own load offsets) exactly as ordinary least
    squares with an intercept does; filter error's model predicts them better on average."""
    from fwid.estimate._equation_error import loads_at_measured_states
    from fwid.simulation._averaged import averaged

    model = fwid.longitudinal()
    fl = fwid.load_flights(*[flights / f"{n}.csv" for n in NAMES])
    exps = [averaged(f, model) for f in fl]

    def r2(y, yh):
        return 1 - np.sum((y - yh) ** 2, 0) / np.sum((y - y.mean(0)) ** 2, 0)

    for a, b in ((0, 1), (1, 0)):
        ea, eb = exps[a], exps[b]

        def X(e):
            return np.column_stack([np.asarray(e.z)[:, :3], np.asarray(e.u)[:, 0],
                                    np.ones(e.n)])

        beta = np.linalg.lstsq(X(ea), np.asarray(ea.forces), rcond=None)[0]
        yb, pred = np.asarray(eb.forces), X(eb) @ beta
        peer = r2(yb, pred - pred.mean(0) + yb.mean(0))  # OLS, the test flight's offsets
        fitted = {m: model.with_params({k: v["value"] for k, v in identified[
            m, NAMES[a]][1]["parameters"].items() if k in model.params})
            for m in ("equation-error", "filter-error")}  # the reports' estimates
        got_ee = r2(yb, loads_at_measured_states(fitted["equation-error"], eb))
        got_fe = r2(yb, loads_at_measured_states(fitted["filter-error"], eb))
        np.testing.assert_allclose(got_ee, peer, atol=1e-6)
        assert np.mean(got_fe) > np.mean(got_ee), (got_fe, got_ee)
