"""The textbook cases of `textbook_cases.py` that need a method other than plain output error
(issue 17): ``tc08`` (multiple shooting), ``tc04_fem``, ``tc02_fem`` (filter error) and the
speed row ``speed_fem_vs_oem``. Each runner returns the case's entry of the JSON file:
``{param: {"value": .., "std": ..}, "_fwid": {...}}``."""

from __future__ import annotations

import time
import warnings

import numpy as np

import _tc08
from _textbook import fwid_model


def _experiments(case):
    import fwid

    return [fwid.Experiment(r["t"], r["u"], r["z"], x0=r["x0"], consts=r["consts"])
            for r in case.records()]


def _table(model, result, names):
    """All `names`, the fixed ones with std 0."""
    out = {}
    for k in names:
        if k in result.names:
            i = result.names.index(k)
            out[k] = {"value": float(result.theta[i]), "std": float(result.std[i])}
        else:
            out[k] = {"value": float(model.params[k]), "std": 0.0, "fixed": True}
    return out


def _timed_fit(model, exps, **kw):
    import fwid

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        res = fwid.fit(model, exps, start="model", **kw)
    return res, time.perf_counter() - t0


def tc08() -> dict:
    """FVSysID TC08, the unstable aircraft, by multiple shooting from the book's start values
    (Zq fixed as the book); the errors from the values the data were simulated with."""
    case = _tc08.CASE
    model = fwid_model(case).with_free(_tc08.FREE)
    exps = _experiments(case)
    res, wall = _timed_fit(model, exps, method="multiple-shooting")
    out = _table(model, res, case.names)
    est = {k: v["value"] for k, v in out.items()}
    eig = _tc08.eigenvalues(est)
    oem, oem_wall = _timed_fit(model, exps)
    oem_est = {**est, **dict(zip(oem.names, map(float, oem.theta)))}
    out["_fwid"] = {
        "method": "multiple-shooting", "converged": bool(res.converged),
        "steps": int(res.steps), "noise": res.noise, "wall_s": wall,
        "eigenvalues": eig.tolist(), "true_eigenvalues": list(_tc08.TRUE_EIGENVALUES),
        "error_pct": {k: 100 * (est[k] / v - 1) for k, v in _tc08.TRUE.items()},
        "eigenvalue_error_pct": (100 * (eig / np.array(_tc08.TRUE_EIGENVALUES) - 1)).tolist(),
        "warnings": list(res.warnings),
        "plain_output_error": {
            "converged": bool(oem.converged), "noise": oem.noise,
            "values": {k: oem_est[k] for k in case.names},
            "eigenvalues": _tc08.eigenvalues(oem_est).tolist(), "wall_s": oem_wall,
            "warnings": list(oem.warnings)},
    }
    print(f"\n{case.title}: multiple shooting "
          f"{'converged' if bool(res.converged) else 'NOT converged'} in {int(res.steps)} "
          f"steps, {wall:.1f} s; eigenvalues {eig.round(4)}")
    for k, v in _tc08.TRUE.items():
        print(f"  {k:<5}{est[k]:>10.5g}  true {v:>9.5g}  {100 * (est[k] / v - 1):+.2f} %")
    print(f"  plain output error: eigenvalues {_tc08.eigenvalues(oem_est).round(4)}")
    return out


RUNNERS = {"tc08": tc08}
