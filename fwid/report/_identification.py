"""The `report.json` of `fwid identify --model lon|lat` (the report format) and the blocks
every pipeline's report shares: parameters, fit information, pooled metrics, mode spread."""

from __future__ import annotations

import numpy as np

from ..validate._metrics import fit_metrics
from ..validate._modes import eigenvalues, modes
from ._bounded import mark_diverged, with_identifiable


def parameters(fit, names=None) -> dict:
    """A fit's parameter table (`value`, `std`, ..., `identifiable`), the per-flight `@i`
    terms left out."""
    table = fit.table()
    keep = names if names is not None else [k for k in fit.names if "@" not in k]
    return with_identifiable({k: table[k] for k in keep if k in table})


def eig_list(eigs) -> list:
    return [[float(np.real(e)), float(np.imag(e))] for e in eigs]


def fit_info(fit, outputs) -> dict:
    """The `fit` block of a report: convergence, steps, cost, the noise covariance R (and
    which: `noise`), the residual colour at the data's bandwidth (`residual_colour`) and, for
    filter error, the gain used (`gain`)."""
    return {"converged": bool(fit.converged), "passes": int(fit.passes),
            "gauss_newton_steps": int(fit.steps), "cost": float(fit.cost),
            "R": np.asarray(fit.R), "noise": getattr(fit, "noise", "full"),
            "outputs": list(outputs),
            "residual_colour": _colour(fit, outputs),
            "warnings": list(getattr(fit, "warnings", ())),
            **({"gain": fit.gain} if getattr(fit, "gain", None) else {})}


def _colour(fit, outputs) -> dict | None:
    """Each output's residual autocorrelation at the data's bandwidth (`FitResult.colour`)."""
    colour = getattr(fit, "colour", None)
    if colour is None:
        return None
    return {k: float(v) for k, v in zip(outputs, np.asarray(colour))}


def fit_warnings_of(fits) -> list[str]:
    """The `warnings` key of a report: every fit's warnings, in order (empty when none)."""
    return [w for f in fits for w in getattr(f, "warnings", ())]


def converged_flags(report: dict) -> list[bool]:
    """Whether each fit behind a report converged (its `fit` block, or each flight's); for
    the combined model, those of its cycle-averaged part, else of its flapping part."""
    if report.get("model") == "combined":
        for part in ("cycle_averaged", "flapping"):
            flags = converged_flags(report.get(part, {}))
            if flags:
                return flags
        return []
    if "per_flight" in report:
        return [bool(p["fit"]["converged"]) for p in report["per_flight"] if "fit" in p]
    return [bool(report["fit"]["converged"])] if "fit" in report else []


def _fit_block(ident, fit, estimation, eigs):
    block = {
        "parameters": parameters(fit),
        "eigenvalues": eig_list(eigs),
        "modes": modes(eigs),
        "metrics": {"estimation": mark_diverged(estimation.metrics, [estimation])},
        "local_parameters": estimation.local_params,
        "correlation": {"names": list(fit.names), "matrix": np.asarray(fit.corr)},
        "fit": fit_info(fit, ident.model.outputs),
    }
    return {**block, **prior_and_bounds([fit])}


def prior_and_bounds(fits, flights=None) -> dict:
    """The `"prior"` (`{name: {"mean", "std"}}`) and `"bounds"` (`{name: {"low", "high",
    "active", "at"}}`, `None` an open side) keys of a report, for fits that used them
    ([`fwid.fit`][]`(prior=, bounds=)`; empty otherwise). Over several fits (one per flight,
    all with the same prior and bounds) a bound is `active` where it is in any of them, and
    `active_in` names those fits' `flights` (`at` is then that of the first)."""
    out = {}
    prior = fits[0].prior_table() if hasattr(fits[0], "prior_table") else {}
    bounds = fits[0].bounds_table() if hasattr(fits[0], "bounds_table") else {}
    if prior:
        out["prior"] = prior
    if bounds and len(fits) > 1:
        for k, b in bounds.items():
            sides = [f.active_bounds.get(k) for f in fits]
            b["active"] = any(sides)
            b["at"] = next((s for s in sides if s), None)
            b["active_in"] = [(flights[i] if flights else i) for i, s in enumerate(sides) if s]
    if bounds:
        out["bounds"] = bounds
    return out


def pooled_metrics(flight_fits) -> dict:
    """Metrics over several flights' samples pooled together (outputs and forces), with
    when a flight's simulation diverged (`fwid.report._bounded.mark_diverged`) where one did."""
    if not flight_fits:
        return {}
    names = list(flight_fits[0].metrics)
    z = np.concatenate([np.stack([{**f.measured, **f.forces_measured}[k] for k in names], -1)
                        for f in flight_fits])
    y = np.concatenate([np.stack([{**f.simulated, **f.forces_simulated}[k] for k in names], -1)
                        for f in flight_fits])
    return mark_diverged(fit_metrics(z, y, names), flight_fits)


def modes_spread(per_flight_modes: list[list[dict]]) -> dict:
    """Mean and spread over flights of each mode (Figures 8 and 11): the oscillatory modes'
    natural frequency and damping, the aperiodic modes' time constants (sorted)."""
    osc = [[m for m in ms if m["kind"] == "oscillatory"] for ms in per_flight_modes]
    ape = [sorted(m["tau"] for m in ms if m["kind"] == "aperiodic") for ms in per_flight_modes]
    out = {"flights": len(per_flight_modes)}

    def std(x):
        return x.std(ddof=1) if len(x) > 1 else 0.0

    if all(osc):
        wn = np.array([o[0]["wn"] for o in osc])
        zeta = np.array([o[0]["zeta"] for o in osc])
        out["oscillatory"] = {"wn_mean": wn.mean(), "wn_std": std(wn), "wn_min": wn.min(),
                              "wn_max": wn.max(), "zeta_mean": zeta.mean(),
                              "zeta_std": std(zeta), "zeta_min": zeta.min(),
                              "zeta_max": zeta.max()}
    k = min(len(a) for a in ape)
    if k:
        taus = np.array([a[:k] for a in ape])
        out["aperiodic_tau"] = [{"mean": taus[:, j].mean(), "std": std(taus[:, j]),
                                 "min": taus[:, j].min(), "max": taus[:, j].max()}
                                for j in range(k)]
    return out


def add_validation(report: dict, validation) -> dict:
    """Add the validation flights' metrics (pooled, and per flight) to a report."""
    if validation:
        report["metrics"]["validation"] = pooled_metrics(validation)
        report["validation_flights"] = [
            {"flight": v.name, "metrics": mark_diverged(v.metrics, [v]),
             "local_parameters": v.local_params}
            for v in validation
        ]
    return report


def identification_report(ident) -> dict:
    """The `report.json` of `fwid identify` (the report format), as a dict.

    **Arguments:**

    - `ident`: an [`fwid.Identification`][].

    **Returns:** a dict with `model`, `flights`, `parameters`, `eigenvalues`, `modes`,
    `metrics`, `state_space` and, with several flights, `per_flight` and `modes_spread`;
    write it with [`fwid.write_json`][].
    """
    model = ident.model
    eigs = ident.eigenvalues
    report = {
        "model": model.name,
        "flights": list(ident.flights),
        "joint": bool(ident.joint),
        "parameters": {},
        "eigenvalues": eig_list(eigs),
        "modes": modes(eigs),
        "metrics": {"estimation": pooled_metrics(ident.estimation)},
        "trim_and_vehicle": ident.consts,
        "state_space": ident.state_space().to_json(),
        "units": "SI: rad, rad/s, m/s, N, N m; rms in the output's unit",
        "warnings": [*getattr(ident, "warnings", ()), *fit_warnings_of(ident.fits)],
        "closed_loop": {c.flight: c.to_json()
                        for c in getattr(ident, "closed_loop", ()) if c is not None},
    }
    add_validation(report, ident.validation)
    if len(ident.fits) == 1:
        block = _fit_block(ident, ident.fit, ident.estimation[0], eigs)
        report["parameters"] = block["parameters"]
        report["correlation"] = block["correlation"]
        report["fit"] = block["fit"]
        report.update(prior_and_bounds(ident.fits))
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
        report["parameters"] = with_identifiable({
            k: {"value": float(vals[:, i].mean()),
                "std": float(vals[:, i].std(ddof=1)) if len(per) > 1 else None,
                "spread_over_flights": True}
            for i, k in enumerate(names)
        })
        report["summary"] = ("top-level parameters are the mean over the per-flight fits; "
                             "their std is the spread (sample std) across flights")
        report["modes_spread"] = modes_spread([p["modes"] for p in per])
        report.update(prior_and_bounds(ident.fits, ident.flights))
    return report
