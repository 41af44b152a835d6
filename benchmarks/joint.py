"""Joint or individual fits: which validates better on held-out flights.

    python benchmarks/joint.py [--seeds 3] [--train 6] [--test 6] [--durations 2.5 4.5]
                               [--axes lon lat] [--out benchmarks/results/joint.json]

For every axis, flight duration and seed, `fwid.write_flights` simulates `train + test`
DelFly-like flights (different inputs, amplitudes, quiet starts and noise); the first `train`
are identified jointly and one by one (`fwid.compare_joint`), the last `test` are held out.
The score of a model on a held-out flight is the mean over the outputs of the RMS error as %
of the output's range, the biases re-estimated on that flight. Reported per case: the joint
score, the median individual model's, the mean of the individual estimates' (what
`fwid identify` reports without `--joint`), their ratio and the verdict; and how far the
identified modes lie from the true ones (Table 3 / Table 6), joint vs each individual fit.
The JSON goes to `--out` and a Markdown table next to it (`.md`).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the fwid of this checkout

import fwid  # noqa: E402
from fwid import synth  # noqa: E402
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)


def _osc(ms):
    osc = [m for m in ms if m["kind"] == "oscillatory"]
    return osc[0] if osc else None


def one_case(axis, duration, seed, n_train, n_test):
    with tempfile.TemporaryDirectory() as tmp:
        synth.write_flights(tmp, n_train + n_test, axis=axis, seed=seed, duration=duration)
        flights = fwid.load_flights(tmp)
    train, test = flights[:n_train], flights[n_train:]
    t0 = time.perf_counter()
    cmp = fwid.compare_joint(train, axis, validate=test)
    wall = time.perf_counter() - t0
    js = fwid.report.joint_report(cmp)
    # the oscillatory mode of every fit, against the simulator's truth (Table 3 / Table 6)
    A = (synth.lon_matrices if axis == "lon" else synth.lat_matrices)(synth.DELFLY)[0]
    true_osc = _osc(fwid.modes(np.linalg.eigvals(A)))
    joint_osc = _osc(cmp.joint.modes)
    ind_osc = [_osc(fwid.modes(fwid.eigenvalues(f.model, cmp.individual.consts)))
               for f in cmp.individual.fits]

    def wn_err(o):
        return None if o is None or true_osc is None else 100 * abs(o["wn"] / true_osc["wn"] - 1)

    ind_err = [e for e in (wn_err(o) for o in ind_osc) if e is not None]
    return {
        "axis": axis, "duration_s": duration, "seed": seed, "train": n_train, "test": n_test,
        "wall_s": wall, **js["summary"],
        "joint_score": float(np.median([r["joint"] for r in js["held_out"]])),
        "individual_median_score": float(np.median([r["individual_median"]
                                                    for r in js["held_out"]])),
        "mean_model_score": float(np.median([r["mean_model"] for r in js["held_out"]])),
        "wn_error_pct_joint": wn_err(joint_osc),
        "wn_error_pct_individual_median": float(np.median(ind_err)) if ind_err else None,
        "wn_error_pct_individual_max": float(np.max(ind_err)) if ind_err else None,
    }


def markdown(res) -> str:
    lines = [
        "# Joint vs individual fits on held-out flights",
        "",
        f"`{res['command']}` ({res['machine']})",
        "",
        "Score: mean over the outputs of the held-out RMS error as % of the output's range "
        "(biases re-estimated on each held-out flight), median over the held-out flights. "
        "Ratio: median over held-out flights of joint / median individual model; below 1 "
        "means the joint model validates better. wn error: the oscillatory mode's natural "
        "frequency against the simulator's truth.",
        "",
        "| axis | duration [s] | seed | joint | individual (median) | mean of individual | "
        "ratio | joint lower on | verdict | wn error joint | wn error individual (median, max) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def f(x, p=2):
        return "-" if x is None else f"{x:.{p}f}"

    for c in res["cases"]:
        lines.append(
            f"| {c['axis']} | {c['duration_s']} | {c['seed']} | {f(c['joint_score'])} | "
            f"{f(c['individual_median_score'])} | {f(c['mean_model_score'])} | "
            f"{f(c['ratio'], 3)} | {c['joint_better_on']}/{c['held_out_flights']} | "
            f"{c['verdict']} | {f(c['wn_error_pct_joint'])} % | "
            f"{f(c['wn_error_pct_individual_median'])} %, "
            f"{f(c['wn_error_pct_individual_max'])} % |")
    lines += ["", "| axis | duration [s] | cases | joint better | tie | individual better | "
              "median ratio |", "|---|---|---|---|---|---|---|"]
    groups = sorted({(c["axis"], c["duration_s"]) for c in res["cases"]})
    for axis, d in groups:
        cs = [c for c in res["cases"] if c["axis"] == axis and c["duration_s"] == d]
        n = {v: sum(c["verdict"] == v for c in cs) for v in ("joint", "tie", "individual")}
        lines.append(f"| {axis} | {d} | {len(cs)} | {n['joint']} | {n['tie']} | "
                     f"{n['individual']} | {np.median([c['ratio'] for c in cs]):.3f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--train", type=int, default=6)
    ap.add_argument("--test", type=int, default=6)
    ap.add_argument("--durations", type=float, nargs="+", default=[2.5, 4.5])
    ap.add_argument("--axes", nargs="+", default=["lon"], choices=("lon", "lat"))
    ap.add_argument("--out", default=str(HERE / "results" / "joint.json"))
    args = ap.parse_args(argv)
    cases = []
    for axis in args.axes:
        for d in args.durations:
            for s in range(args.seeds):
                c = one_case(axis, d, 1000 * s + 17, args.train, args.test)
                cases.append(c)
                print(f"{axis} {d:.1f} s seed {c['seed']}: joint {c['joint_score']:.2f} "
                      f"individual {c['individual_median_score']:.2f} mean-model "
                      f"{c['mean_model_score']:.2f} -> {c['verdict']} ({c['wall_s']:.0f} s)",
                      flush=True)
    res = {"command": "python benchmarks/joint.py " + " ".join(argv or sys.argv[1:]),
           "machine": f"{platform.machine()}, {os.cpu_count()} CPUs",
           "cases": cases}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(_provenance.json_text(res, indent=1))
    out.with_suffix(".md").write_text(_provenance.markdown(markdown(res)))
    print(markdown(res))
    print(f"wrote {out} and {out.with_suffix('.md')}")


if __name__ == "__main__":
    main()
