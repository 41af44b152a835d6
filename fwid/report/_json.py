"""Machine-readable reports (CONTRACTS section 3), written whole or not at all."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from ..validate._metrics import fit_metrics
from ..validate._modes import eigenvalues, modes


def _clean(obj):
    """JSON-safe: numpy scalars/arrays to Python, NaN/inf to None."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray) or hasattr(obj, "__jax_array__") or type(obj).__module__.startswith("jax"):
        return _clean(np.asarray(obj).tolist())
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        return x if math.isfinite(x) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def write_json(path: str | Path, obj) -> Path:
    """Write `obj` as JSON atomically: to a temporary file beside `path`, then renamed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(_clean(obj), indent=2)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text + "\n")
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def _parameters(fit, names=None):
    table = fit.table()
    keep = names if names is not None else [k for k in fit.names if "@" not in k]
    return {k: table[k] for k in keep if k in table}


def _eig_list(eigs):
    return [[float(np.real(e)), float(np.imag(e))] for e in eigs]


def _fit_block(ident, fit, estimation, eigs):
    return {
        "parameters": _parameters(fit),
        "eigenvalues": _eig_list(eigs),
        "modes": modes(eigs),
        "metrics": {"estimation": estimation.metrics},
        "local_parameters": estimation.local_params,
        "correlation": {"names": list(fit.names), "matrix": np.asarray(fit.corr)},
        "fit": {
            "converged": bool(fit.converged), "passes": int(fit.passes),
            "gauss_newton_steps": int(fit.steps), "cost": float(fit.cost),
            "R": np.asarray(fit.R), "outputs": list(ident.model.outputs),
        },
    }


def pooled_metrics(flight_fits) -> dict:
    """Metrics over several flights' samples pooled together (outputs and forces)."""
    if not flight_fits:
        return {}
    names = list(flight_fits[0].metrics)
    z = np.concatenate([np.stack([{**f.measured, **f.forces_measured}[k] for k in names], -1)
                        for f in flight_fits])
    y = np.concatenate([np.stack([{**f.simulated, **f.forces_simulated}[k] for k in names], -1)
                        for f in flight_fits])
    return fit_metrics(z, y, names)


def modes_spread(per_flight_modes: list[list[dict]]) -> dict:
    """Mean and spread over flights of each mode (Figures 8 and 11): the oscillatory modes'
    natural frequency and damping, the aperiodic modes' time constants (sorted)."""
    osc = [[m for m in ms if m["kind"] == "oscillatory"] for ms in per_flight_modes]
    ape = [sorted(m["tau"] for m in ms if m["kind"] == "aperiodic") for ms in per_flight_modes]
    out = {"flights": len(per_flight_modes)}
    if all(osc):
        wn = np.array([o[0]["wn"] for o in osc])
        zeta = np.array([o[0]["zeta"] for o in osc])
        out["oscillatory"] = {"wn_mean": wn.mean(), "wn_std": wn.std(ddof=1) if len(wn) > 1 else 0.0,
                              "zeta_mean": zeta.mean(),
                              "zeta_std": zeta.std(ddof=1) if len(zeta) > 1 else 0.0}
    k = min(len(a) for a in ape)
    if k:
        taus = np.array([a[:k] for a in ape])
        out["aperiodic_tau"] = [{"mean": taus[:, j].mean(), "min": taus[:, j].min(),
                                 "max": taus[:, j].max()} for j in range(k)]
    return out


def add_validation(report: dict, validation) -> dict:
    """Add the validation flights' metrics (pooled, and per flight) to a report."""
    if validation:
        report["metrics"]["validation"] = pooled_metrics(validation)
        report["validation_flights"] = [
            {"flight": v.name, "metrics": v.metrics, "local_parameters": v.local_params}
            for v in validation
        ]
    return report


def identification_report(ident) -> dict:
    """The `report.json` of `fwid identify` (CONTRACTS section 3), as a dict."""
    model = ident.model
    eigs = ident.eigenvalues
    report = {
        "model": model.name,
        "flights": list(ident.flights),
        "joint": bool(ident.joint),
        "parameters": {},
        "eigenvalues": _eig_list(eigs),
        "modes": modes(eigs),
        "metrics": {"estimation": pooled_metrics(ident.estimation)},
        "trim_and_vehicle": ident.consts,
        "units": "SI: rad, rad/s, m/s, N, N m; rms in the output's unit",
    }
    add_validation(report, ident.validation)
    if len(ident.fits) == 1:
        block = _fit_block(ident, ident.fit, ident.estimation[0], eigs)
        report["parameters"] = block["parameters"]
        report["correlation"] = block["correlation"]
        report["fit"] = block["fit"]
        if ident.joint and len(ident.flights) > 1:
            report["local_parameters"] = {
                k: {"value": v["value"], "std": v["std"]}
                for k, v in ident.fit.table().items() if "@" in k
            }
    else:
        per = []
        for f, est in zip(ident.fits, ident.estimation):
            block = _fit_block(ident, f, est, eigenvalues(f.model, ident.consts))
            per.append({"flight": est.name, **block})
        report["per_flight"] = per
        names = [k for k in model.free]
        vals = np.array([[p["parameters"][k]["value"] for k in names] for p in per])
        report["parameters"] = {
            k: {"value": float(vals[:, i].mean()),
                "std": float(vals[:, i].std(ddof=1)) if len(per) > 1 else None,
                "spread_over_flights": True}
            for i, k in enumerate(names)
        }
        report["summary"] = ("top-level parameters are the mean over the per-flight fits; "
                             "their std is the spread (sample std) across flights")
        report["modes_spread"] = modes_spread([p["modes"] for p in per])
    return report
