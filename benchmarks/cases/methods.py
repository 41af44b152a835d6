"""The textbook cases of `textbook_cases.py` that need a method other than plain output error:
``tc08`` (multiple shooting), ``tc04_fem``, ``tc02_fem`` (filter error) and the
speed row ``speed_fem_vs_oem``. Each runner returns the case's entry of the JSON file:
``{param: {"value": .., "std": ..}, "_fwid": {...}}``."""

from __future__ import annotations

import time
import warnings

import numpy as np

from . import tc02
from . import tc04
from . import tc08 as tc08_case
from .textbook import fwid_model

#: The book's filter-error estimates of TC04 (chapter 7 ``mDefCase04``, ``parFEM``).
TC04_FEM_BOOK = dict(CD0=0.122688, CDa=0.320055, CLa=4.32785, Cma=-0.967854, Cmq=-34.7098,
                     Cmde=-1.52913)


def _experiments(case):
    import fwid

    return [fwid.Experiment(r["t"], r["u"], r["z"], x0=r["x0"], consts=r["consts"])
            for r in case.records()]


def _table(model, result, names):
    """All `names`, the fixed ones (values from `model`) with std 0."""
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
    case = tc08_case.CASE
    model = fwid_model(case).with_free(tc08_case.FREE)
    exps = _experiments(case)
    res, wall = _timed_fit(model, exps, method="multiple-shooting")
    out = _table(model, res, case.names)
    est = {k: v["value"] for k, v in out.items()}
    eig = tc08_case.eigenvalues(est)
    oem, oem_wall = _timed_fit(model, exps)
    oem_est = {**est, **dict(zip(oem.names, map(float, oem.theta)))}
    out["_fwid"] = {
        "method": "multiple-shooting", "converged": bool(res.converged),
        "steps": int(res.steps), "noise": res.noise, "wall_s": wall,
        "eigenvalues": eig.tolist(), "true_eigenvalues": list(tc08_case.TRUE_EIGENVALUES),
        "error_pct": {k: 100 * (est[k] / v - 1) for k, v in tc08_case.TRUE.items()},
        "eigenvalue_error_pct":
            (100 * (eig / np.array(tc08_case.TRUE_EIGENVALUES) - 1)).tolist(),
        "warnings": list(res.warnings),
        "plain_output_error": {
            "converged": bool(oem.converged), "noise": oem.noise,
            "values": {k: oem_est[k] for k in case.names},
            "eigenvalues": tc08_case.eigenvalues(oem_est).tolist(), "wall_s": oem_wall,
            "warnings": list(oem.warnings)},
    }
    print(f"\n{case.title}: multiple shooting "
          f"{'converged' if bool(res.converged) else 'NOT converged'} in {int(res.steps)} "
          f"steps, {wall:.1f} s; eigenvalues {eig.round(4)}")
    for k, v in tc08_case.TRUE.items():
        print(f"  {k:<5}{est[k]:>10.5g}  true {v:>9.5g}  {100 * (est[k] / v - 1):+.2f} %")
    print(f"  plain output error: eigenvalues {tc08_case.eigenvalues(oem_est).round(4)}")
    return out


def _fem_entry(case, res, wall, names):
    out = _table(None, res, (*names, *(f"F_{s}" for s in case.states)))
    eig = np.linalg.eigvals(np.asarray(res.model.state_matrices(
        res.model.params, {}, x0=case.records()[0]["x0"],
        u0=case.records()[0]["u"][0])[0]))
    out["_fwid"] = {"method": "filter-error", "converged": bool(res.converged),
                    "relaxation_passes": res.outer, "steps": int(res.steps),
                    "noise": res.noise, "wall_s": wall, "white": res.white,
                    "whiteness": res.whiteness, "F": np.asarray(res.F).tolist(),
                    "eigenvalues": [[float(e.real), float(e.imag)] for e in eig],
                    "stable": bool(np.all(eig.real < 0)), "warnings": list(res.warnings)}
    state = "converged" if bool(res.converged) else "NOT converged"
    print(f"\n{case.title}: filter error {state} in {res.outer} passes "
          f"({int(res.steps)} steps), {wall:.1f} s "
          f"(compilation included); innovations white: {res.white}; "
          f"stable: {out['_fwid']['stable']}")
    return out


def tc04_fem() -> dict:
    """FVSysID TC04 (HFB-320) by the filter-error method from the book's start values (F too),
    against the book's filter-error estimates."""
    case = tc04.CASE
    res, wall = _timed_fit(fwid_model(case), _experiments(case), method="filter-error",
                           process_noise=tc04.F0)
    out = _fem_entry(case, res, wall, case.names)
    diff = {k: 100 * (out[k]["value"] / v - 1) for k, v in TC04_FEM_BOOK.items()}
    out["_published"] = {"values": TC04_FEM_BOOK, "diff_pct": diff,
                         "source": "Jategaonkar (2015) companion software, "
                                   "chapter07/mDefCase04.m, parFEM"}
    for k, v in TC04_FEM_BOOK.items():
        print(f"  {k:<5}{out[k]['value']:>11.6g}  book {v:>10.6g}  {diff[k]:+.2f} %")
    return out


def tc02_fem() -> dict:
    """FVSysID TC02 (lateral-directional in turbulence) by the filter-error method from the
    book's start values."""
    case = tc02.CASE
    res, wall = _timed_fit(fwid_model(case), _experiments(case), method="filter-error",
                           process_noise=tc02.F0)
    return _fem_entry(case, res, wall, case.names)


def speed_fem_vs_oem(repeats: int = 5) -> dict:
    """Filter error against output error on TC04, both from the book's start values: the
    first call (compilation included) and the median of `repeats` warm calls. Output error
    with its default `noise="auto"` (a full-R fit, then a diagonal-R one: two fits) and
    with `noise="diagonal"` (one fit, the R the filter error uses); the ratios against the
    default."""
    case = tc04.CASE
    model, exps = fwid_model(case), _experiments(case)
    out = {}
    for key, kw in (("oem", {}), ("oem_diagonal", dict(noise="diagonal")),
                    ("fem", dict(method="filter-error", process_noise=tc04.F0))):
        _, first = _timed_fit(model, exps, **kw)
        warm = [_timed_fit(model, exps, **kw)[1] for _ in range(repeats)]
        out[key] = {"first_s": first, "warm_median_s": float(np.median(warm))}
    out["ratio_warm"] = out["fem"]["warm_median_s"] / out["oem"]["warm_median_s"]
    out["ratio_first"] = out["fem"]["first_s"] / out["oem"]["first_s"]
    print(f"\nspeed, TC04: output error {out['oem']['warm_median_s']:.2f} s warm "
          f"({out['oem']['first_s']:.1f} s first), filter error "
          f"{out['fem']['warm_median_s']:.2f} s warm ({out['fem']['first_s']:.1f} s first): "
          f"{out['ratio_warm']:.2f}x warm, {out['ratio_first']:.2f}x first")
    return out


def gust_fem_vs_oem(n_flights: int = 8, strength: float = 1.0, seed: int = 500) -> dict:
    """Simulated DelFly longitudinal flights in gusts (`fwid.synth.write_flights(...,
    effect="turbulence")`, as `fwid simulate --effect turbulence`), cycle-averaged as
    `fwid.identify` does, each fitted by output error and by filter error with the defaults
    (least-squares start; F from `_default_f`): the relative errors of the 12 derivatives of
    Table 1 from the simulator's truth."""
    import tempfile
    from pathlib import Path

    import fwid
    from fwid import synth
    from fwid.identification._cycle_averaged import averaged, get_model

    model = get_model("lon")
    truth = synth.DELFLY.params()
    names = list(fwid.models.TABLE1)
    tru = np.array([truth[k] for k in names])
    rows = []
    with tempfile.TemporaryDirectory() as d:
        paths = synth.write_flights(Path(d), n_flights=n_flights, axis="lon", seed=seed,
                                    effect="turbulence", strength=strength)
        for path in paths:
            e = averaged(fwid.load_flight(path), model, 5.0, 40.0)
            row = {"flight": path.name}
            for key, kw in (("oem", {}), ("fem", dict(method="filter-error"))):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    r = fwid.fit(model, e, **kw)
                est = np.array([float(r.theta[r.names.index(k)]) for k in names])
                rel = np.abs(est / tru - 1)
                row[key] = {"converged": bool(r.converged),
                            "median_rel_error": float(np.median(rel)),
                            "rel_error": dict(zip(names, rel.tolist()))}
            rows.append(row)
    med = {k: float(np.median([r[k]["median_rel_error"] for r in rows])) for k in ("oem",
                                                                                   "fem")}
    better = sum(r["fem"]["median_rel_error"] < r["oem"]["median_rel_error"] for r in rows)
    print(f"\nDelFly lon in gusts ({n_flights} flights, strength {strength}): median over "
          f"flights of the median relative error of the 12 derivatives: output error "
          f"{100 * med['oem']:.1f} %, filter error {100 * med['fem']:.1f} %; filter error "
          f"closer on {better}/{n_flights} flights")
    return {"flights": rows, "median_rel_error": med, "fem_closer_flights": better,
            "n_flights": n_flights, "strength": strength, "seed": seed}


RUNNERS = {"tc08": tc08, "tc04_fem": tc04_fem, "tc02_fem": tc02_fem,
           "speed_fem_vs_oem": speed_fem_vs_oem, "gust_fem_vs_oem": gust_fem_vs_oem}
