"""The identified model a design starts from: a `report.json`, an identification, or a model.

A design needs the model at its estimate, the per-flight constants (trim, vehicle) and the
measurement noise covariance `R`. `report.json` holds all three: `parameters`,
`trim_and_vehicle` and `fit.R` (the ML estimate of R, Eq. 11, from the fit's residuals).
Where `fit.R` is missing (a report of several flights fitted one by one keeps it per flight
and the mean over them is taken; an older or hand-written report may have none), the
estimation metrics' `rms` per output gives a diagonal `R = diag(rms^2)`; the design says
which it used (`noise`).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .._errors import InputError
from ..models._delfly import lateral, longitudinal
from ..models._greybox import GreyBoxModel

#: The designed control and the attitude state bounded, by model.
CONTROL = {"lon": "de", "lat": "dr"}
ATTITUDE = {"lon": "theta", "lat": "phi"}
OTHER = {"lon": "dr", "lat": "de"}


def _read(path) -> dict:
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such report; give the report.json that `fwid identify "
                         "--out DIR` wrote (DIR/report.json)")
    try:
        return json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: not a JSON report ({exc}); give the report.json of "
                         "`fwid identify`") from None


def _noise(report: dict, outputs, where: str) -> tuple[np.ndarray, str]:
    fits = [report.get("fit")] if report.get("fit") else [
        p.get("fit") for p in report.get("per_flight", []) if p.get("fit")]
    Rs = [np.asarray(f["R"], float) for f in fits if f and f.get("R") is not None
          and list(f.get("outputs", outputs)) == list(outputs)]
    if Rs and all(R.shape == (len(outputs), len(outputs)) for R in Rs):
        return np.mean(Rs, axis=0), "fit.R (the ML noise covariance of the fit, Eq. 11)"
    est = report.get("metrics", {}).get("estimation", {})
    missing = [k for k in outputs if est.get(k, {}).get("rms") is None]
    if missing:
        raise InputError(f"{where}: neither fit.R nor metrics.estimation rms of "
                         f"{', '.join(missing)}; give a report written by `fwid identify`")
    return (np.diag([float(est[k]["rms"]) ** 2 for k in outputs]),
            "diag(rms^2) of the estimation metrics (no fit.R in the report)")


def from_report(report, model: str | None = None) -> tuple[GreyBoxModel, dict, np.ndarray, str]:
    """The model, constants, `R` and how `R` was found, from a `report.json` (a path or the
    parsed dict). `model` (`"lon"`/`"lat"`), when given, must be the report's."""
    where = str(report) if not isinstance(report, dict) else "report"
    rep = _read(report) if not isinstance(report, dict) else report
    kind = rep.get("model")
    if kind not in ("lon", "lat"):
        raise InputError(f"{where}: a report of the {kind!r} model; designs need a `fwid "
                         "identify --model lon` or `--model lat` report")
    if model is not None and model != kind:
        raise InputError(f"{where}: the report is of the {kind!r} model, not {model!r}; give "
                         f"--model {kind} or a report of `fwid identify --model {model}`")
    base = longitudinal() if kind == "lon" else lateral()
    params = rep.get("parameters") or {}
    missing = [k for k in base.free if k not in params and k not in base.local]
    if missing:
        raise InputError(f"{where}: parameters {', '.join(missing)} are missing; give the "
                         "report.json of `fwid identify`")
    values = {k: float(params[k]["value"]) for k in base.free if k in params
              and k not in base.local}
    consts = rep.get("trim_and_vehicle")
    if not consts or any(k not in consts for k in base.constants):
        need = ", ".join(base.constants)
        raise InputError(f"{where}: no trim_and_vehicle block with {need}; give the "
                         "report.json of `fwid identify`")
    R, noise = _noise(rep, base.outputs, where)
    return base.with_params(values), {k: float(consts[k]) for k in base.constants}, R, noise


def from_identification(ident) -> tuple[GreyBoxModel, dict, np.ndarray, str]:
    """The model (its biases at zero: the flight starts at trim), constants and `R` of an
    `Identification` (its first fit's R)."""
    model = ident.model
    model = model.with_params({k: 0.0 for k in model.local})
    consts = {k: float(np.asarray(v)) for k, v in dict(ident.consts).items()
              if k in model.constants}
    return model, consts, np.asarray(ident.fit.R, float), "fit.R of the identification"


def report_prior(report) -> dict | None:
    """The Gaussian prior the report's fit used (`"prior"`: `{name: {"mean", "std"}}`, written
    by `fwid identify` when `fwid.fit(prior=...)` had one) as `{name: std}`, or `None`: a design
    from such a report counts the prior's information once, beside the flights'."""
    rep = _read(report) if not isinstance(report, dict) else report
    prior = rep.get("prior") or {}
    out = {k: float(v["std"]) for k, v in prior.items()
           if isinstance(v, dict) and v.get("std") not in (None, 0)}
    return out or None
