"""Textbook output-error cases fitted with fwid's public API and its default settings.

    python benchmarks/textbook_cases.py --json OUT.json [--reference] [--cases tc01,..]

Writes ``{case: {param: {"value": .., "std": ..}}}`` for

* ``tc01``: FVSysID test case 1, ATTAS lateral-directional, 5 outputs, 22 parameters
  (`tc01.py`);
* ``tc04_oem``: FVSysID test case 4, HFB-320 longitudinal nonlinear model, 7 outputs
  (`tc04.py`);
* ``twin_otter_tlonss``: SIDPAC's Twin Otter `tlonss` demo, outputs alpha, q, az, ``p1..p9``
  (`twin_otter.py`);
* ``tc08``: FVSysID test case 8, the unstable aircraft, by ``method="multiple-shooting"``
  (`tc08.py`, `cases/methods.py`; with the errors from the true values);
* ``tc04_fem``: test case 4 by ``method="filter-error"``, against the book's filter-error
  estimates; ``tc02_fem``: test case 2, lateral-directional in turbulence (`tc02.py`), by
  filter error (converged, stable, innovations white);
* ``speed_fem_vs_oem``: the time of the filter-error fit of TC04 against the output-error one;
* ``gust_fem_vs_oem``: simulated DelFly flights in gusts, filter error against output error
  (relative errors of the derivatives from the simulator's truth);

``--cases`` also takes the cases output error cannot do well, where what counts is that fwid
says so (no reference; their warnings are in ``"_fwid"``):

* ``tc08_unstable``: FVSysID test case 8, an unstable aircraft's short period (`tc08.py`);
* ``tc02_turbulence``: FVSysID test case 2, lateral motion simulated with turbulence
  (`tc02.py`).

``--reference`` also fits each case with the independent numpy/scipy estimator
(`peers/scipy_output_error.py`, diagonal R as FVSysID and SIDPAC) and adds, per case, the key
``"_reference"`` (the same layout) and ``"_agreement"`` (relative difference per parameter,
worst first) and ``"_fwid"`` (steps, converged, the R used, warnings, wall time). The data are
read from ``../shared/flightdata`` (or ``$FWID_FLIGHTDATA_ROOT``), never copied.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from cases import tc01  # noqa: E402
from cases import tc02  # noqa: E402
from cases import tc04  # noqa: E402
from cases import tc08  # noqa: E402
from cases import twin_otter  # noqa: E402
from cases.methods import RUNNERS  # noqa: E402
from cases.textbook import agreement, as_table, fit_fwid, fit_reference, fwid_table  # noqa: E402
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)

CASES = {"tc01": lambda: tc01.CASE, "tc04_oem": lambda: tc04.CASE,
         "twin_otter_tlonss": twin_otter.case}
#: no reference: these check that fwid's warnings name the problem
HARD = {"tc08_unstable": lambda: tc08.CASE, "tc02_turbulence": lambda: tc02.CASE}


def run_case(key: str, reference: bool) -> dict:
    if key in RUNNERS:  # another method than plain output error: no scipy reference
        return RUNNERS[key]()
    case = {**CASES, **HARD}[key]()
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        res = fit_fwid(case)
    wall = time.perf_counter() - t0
    out = fwid_table(case, res)
    print(f"\n{case.title}: fwid {'converged' if bool(res.converged) else 'NOT converged'} in "
          f"{int(res.steps)} steps, R {res.noise}, {wall:.1f} s (compilation included)")
    for w in res.warnings:
        print(f"  warning: {w}")
    if key in HARD:
        out["_fwid"] = {"steps": int(res.steps), "converged": bool(res.converged),
                        "noise": res.noise, "warnings": list(res.warnings), "wall_s": wall}
    if not reference or key in HARD:
        return out
    t0 = time.perf_counter()
    ref = fit_reference(case)
    ref_wall = time.perf_counter() - t0
    ref_table = as_table(case.names, ref["theta"], ref["std"])
    agree = agreement(case, out, ref_table)
    print(f"  reference (numpy RK4 + scipy, diagonal R): {ref['n_iter']} relaxations, "
          f"{ref_wall:.1f} s")
    print(f"  {'param':<6}{'fwid':>13}{'std':>10}{'reference':>13}{'diff %':>9}"
          f"{'published':>12}")
    for k in case.names:
        pub = case.published.get(k)
        print(f"  {k:<6}{out[k]['value']:>13.6g}{out[k]['std']:>10.2g}"
              f"{ref_table[k]['value']:>13.6g}{100 * agree[k]['rel']:>9.4f}"
              + (f"{pub:>12.5g}" if pub is not None else ""))
    worst = max(agree, key=lambda k: agree[k]["rel"] if not agree[k]["near_zero"] else 0)
    print(f"  largest relative difference: {worst} {100 * agree[worst]['rel']:.4f} %; "
          f"all within 0.5 %: {all(a['ok'] for a in agree.values())}")
    out["_reference"] = ref_table
    out["_agreement"] = agree
    out["_fwid"] = {"steps": int(res.steps), "converged": bool(res.converged),
                    "noise": res.noise, "warnings": list(res.warnings), "wall_s": wall,
                    "reference_wall_s": ref_wall}
    if case.published:
        out["_published"] = {"values": case.published, "source": case.source}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", required=True, help="where to write the estimates")
    ap.add_argument("--reference", action="store_true",
                    help="also fit the independent reference and compare")
    ap.add_argument("--cases", default=",".join(CASES),
                    help=f"comma-separated case keys (also: {', '.join((*HARD, *RUNNERS))})")
    args = ap.parse_args(argv)
    out = {k: run_case(k, args.reference) for k in args.cases.split(",")}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(_provenance.json_text(out, indent=2))
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
