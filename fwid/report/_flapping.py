"""The `report.json` of `fwid identify --model flap|combined` (the report format): the
Fourier model (Table 7, Table 8) and the combined model (Sections V-VI)."""

from __future__ import annotations

import numpy as np

from ..identification._combined import CombinedIdentification
from ..identification._flapping import FlappingIdentification
from ..models._fourier import fourier_param_names, fourier_structure
from ..models._greybox import GreyBoxModel
from ..validate._modes import modes
from ._identification import (
    add_validation,
    eig_list,
    fit_info,
    fit_warnings_of,
    identification_report,
    parameters,
    pooled_metrics,
)


def flapping_report(ident: FlappingIdentification, steady=None) -> dict:
    """The `report.json` of `fwid identify --model flap` (the report format), as a dict.

    `parameters` holds Table 7 (`value`, `std`, ...), `metrics` Table 8 per output (pooled over
    flights); `eigenvalues` is empty (a Fourier series has no dynamics). Extra keys:
    `phase_offsets`, `flapping_frequency`, `peaks`, and `steady_vs_manoeuvre` when given.
    """
    outputs, harmonics = fourier_structure(ident.model)
    report = {
        "model": "flap",
        "flights": list(ident.flights),
        "joint": ident.joint,
        "outputs": list(outputs),
        "harmonics": harmonics,
        "parameters": {},
        "eigenvalues": [],
        "metrics": {"estimation": pooled_metrics(ident.estimation)},
        "phase_offsets": dict(ident.phase_offsets),
        "flapping_frequency": dict(ident.frequencies),
        "peaks": ident.peaks,
        "units": "SI: N, N m; phase offsets in rad; rms in the output's unit",
        "warnings": fit_warnings_of(ident.fits),
    }
    if len(ident.fits) == 1:
        report["parameters"] = parameters(ident.fit)
        report["correlation"] = {"names": list(ident.fit.names),
                                 "matrix": np.asarray(ident.fit.corr)}
        report["fit"] = fit_info(ident.fit, outputs)
    else:
        per = [{"flight": est.name, "parameters": parameters(r), "eigenvalues": [],
                "metrics": {"estimation": est.metrics}, "fit": fit_info(r, outputs)}
               for r, est in zip(ident.fits, ident.estimation)]
        report["per_flight"] = per
        names = list(ident.model.free)
        vals = np.array([[p["parameters"][k]["value"] for k in names] for p in per])
        report["parameters"] = {
            k: {"value": float(vals[:, i].mean()), "std": float(vals[:, i].std(ddof=1)),
                "spread_over_flights": True}
            for i, k in enumerate(names)
        }
        report["summary"] = ("top-level parameters are the mean over the per-flight fits "
                             "(phase-aligned to the first flight); their std is the spread")
    if ident.validation:
        report["metrics"]["validation"] = pooled_metrics(ident.validation)
        report["validation_flights"] = [
            {"flight": v.name, "metrics": v.metrics,
             "phase_offset": v.local_params["phase_offset"]}
            for v in ident.validation
        ]
    if steady:
        report["steady_vs_manoeuvre"] = {
            s.flight: {"split_index": s.split, "frequency": s.frequency, **s.summary}
            for s in steady
        }
    return report


def combined_report(ident: CombinedIdentification) -> dict:
    """The `report.json` of `fwid identify --model combined` (the report format).

    `parameters` holds both sub-models' parameters, `eigenvalues` those of the cycle-averaged
    part, `metrics` the full simulation's match per state and force. The sub-models' own
    reports are under `cycle_averaged` and `flapping`; `peaks` compares the first flapping
    peaks of every state and force, measured vs model.
    """
    eigs = ident.eigenvalues
    if ident.cycle is not None:
        cyc = identification_report(ident.cycle)
    else:  # a given cycle-averaged model: its values, no uncertainty
        m = ident.model
        cyc = {"model": m.name, "given": True, "modes": modes(eigs),
               "parameters": {k: {"value": float(m.params[k]), "std": None}
                              for k in m.free if k not in m.local and k in _cycle_names(m)}}
    flap = flapping_report(ident.flapping)
    report = {
        "model": "combined",
        "flights": list(ident.flights),
        "joint": bool(ident.flapping.joint),
        "parameters": {**cyc["parameters"], **flap["parameters"]},
        "eigenvalues": eig_list(eigs),
        "modes": cyc.get("modes", []),
        "metrics": {"estimation": pooled_metrics(ident.estimation)},
        "phase_offsets": dict(ident.flapping.phase_offsets),
        "flapping_frequency": dict(ident.frequencies),
        "peaks": ident.peaks,
        "cycle_averaged": cyc,
        "flapping": flap,
        "units": "SI: rad, rad/s, m/s, N, N m; rms in the output's unit",
        "warnings": list(cyc.get("warnings", [])) + list(flap["warnings"]),
    }
    return add_validation(report, ident.validation)


def _cycle_names(model: GreyBoxModel) -> set[str]:
    outputs, harmonics = (model.f.outputs, model.f.harmonics)
    return set(model.params) - set(fourier_param_names(outputs, harmonics))
