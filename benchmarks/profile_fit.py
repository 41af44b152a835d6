"""Where fwid's time goes on one flight of the speed benchmark's problem.

    python benchmarks/profile_fit.py [--out benchmarks/results/profile.json] [--seed 0]
                                     [--start true1.2|least-squares]

(`python benchmarks/speed.py --profile` runs the same after its tables and puts it in
speed.json under "profile" and in speed.md.) On the problem of `cases/delfly_speed.py`:

- micro-benchmarks of fwid's parts against a `lax.scan` RK4: the simulation, `jacfwd` through
  diffrax, and the one-solve outputs + sensitivities that fwid's estimator runs per
  Gauss-Newton step;
- fwid.fit, its batched call, and the hand-written JAX reference's jit and vmap timed
  round-robin (15 rounds, so all see the same load), and their ratios; Gauss-Newton steps per
  relaxation pass and time per step or iteration;
- what-ifs: fwid's own `_fit_batch` compiled as fwid.fit calls it for one flight, as is and
  with `simulate` / `simulate_sensitivities` in `fwid.estimate._output_error` patched to a
  `lax.scan` RK4 with jacfwd *in this process only* (fwid's files are not touched).
"""

from __future__ import annotations

import argparse
import functools
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))  # the fwid of this checkout, not another installed one

from cases.delfly_speed import DT, lon_f_jax, setup  # noqa: E402  (first: imports fwid, float64 on)

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import fwid  # noqa: E402
from fwid.estimate import _output_error as _oe  # noqa: E402

import _shared as M  # noqa: E402
from peers.jax_output_error import rk4_scan  # noqa: E402
from _shared import Bench  # noqa: E402

N_FLIGHTS = 4  # the batched calls of the interleaved timings fit flights 0-3


def run_profile(B, fit_warm_s=None):
    """Micro-benchmarks of fwid's parts against the scan, and what-ifs (runtime patches).

    `B` a `_methods.Bench` with at least one flight (the interleaved batched calls take up to
    4); `fit_warm_s` fwid.fit's warm time from speed.py's table, recorded next to the
    interleaved one."""
    print("profile: where fwid's time goes", flush=True)
    prof = {}
    exp = B.exps[0]
    sm, fb_args = B.fit_batch_args(0)
    theta0 = jnp.asarray(B.starts[0])
    c0 = {k: jnp.asarray(v) for k, v in B.F["consts_list"][0].items()}
    u0 = jnp.asarray(B.F["u"][0])
    x00 = jnp.asarray(B.F["x0"][0])

    def sim_diffrax(th):
        return fwid.simulate(sm, exp, sm.merge(th))[1]

    def sim_scan(th):
        return rk4_scan(lon_f_jax, th, x00, u0, DT, c0)

    parts = [("simulate, diffrax (fwid.simulate)", sim_diffrax),
             ("simulate, lax.scan RK4", sim_scan),
             ("jacfwd(simulate), diffrax ForwardMode", jax.jacfwd(sim_diffrax)),
             ("jacfwd(simulate), lax.scan RK4", jax.jacfwd(sim_scan))]
    if hasattr(_oe, "simulate_sensitivities"):  # what fwid's estimator runs per GN step
        parts.insert(3, ("outputs + sensitivities, diffrax (one solve)",
                         lambda th: _oe.simulate_sensitivities(sm, exp, sm.merge, th)))
    micro = {}
    for name, fn in parts:
        compiled, tl, tc = M.aot(fn, theta0)
        med, mn = M.warm_times(compiled, theta0)
        micro[name] = dict(run_ms=1e3 * med, run_min_ms=1e3 * mn, trace_lower_s=tl,
                           compile_s=tc)
        print(f"  {name:<44} {1e3 * med:8.3f} ms (min {1e3 * mn:.3f})  trace+lower {tl:5.2f} s  "
              f"compile {tc:5.2f} s", flush=True)
    d = np.max(np.abs(np.asarray(sim_diffrax(theta0)) - np.asarray(sim_scan(theta0))))
    micro["max_abs_diff_diffrax_vs_scan"] = float(d)
    prof["micro"] = micro
    # The headline ratios, measured round-robin so that every method sees the same load.
    fit_one, fit_many = B.ref
    a1 = B.ref_args_one()
    nb = min(4, len(B.starts))
    fbc, ar = B.fwid_batched(nb), B.ref_args(nb)
    calls = {"fwid.fit (N=1)": lambda: B.fwid_fit(0),
             "JAX reference jit (N=1)": lambda: M.block(fit_one(*a1)),
             f"{B.batched_label} (N={nb})": fbc,
             f"JAX reference vmap (N={nb})": lambda: M.block(fit_many(*ar))}
    il = M.interleaved(calls, 15)  # compiled already by speed.py's tables, if it ran them
    names = list(calls)
    il["ratios"] = {
        "fwid.fit / reference (N=1)": dict(
            median=il[names[0]]["median_s"] / il[names[1]]["median_s"],
            min=il[names[0]]["min_s"] / il[names[1]]["min_s"]),
        f"{B.batched_label} / reference vmap (N={nb})": dict(
            median=il[names[2]]["median_s"] / il[names[3]]["median_s"],
            min=il[names[2]]["min_s"] / il[names[3]]["min_s"]),
        f"{B.batched_label} (N={nb}) / fwid.fit (N=1)": dict(
            median=il[names[2]]["median_s"] / il[names[0]]["median_s"],
            min=il[names[2]]["min_s"] / il[names[0]]["min_s"]),
        f"reference vmap (N={nb}) / reference jit (N=1)": dict(
            median=il[names[3]]["median_s"] / il[names[1]]["median_s"],
            min=il[names[3]]["min_s"] / il[names[1]]["min_s"]),
    }
    prof["interleaved"] = il
    for k in names:
        print(f"  interleaved {k:<28} median {il[k]['median_s']:.4f} s  min {il[k]['min_s']:.4f} s",
              flush=True)
    for k, v in il["ratios"].items():
        print(f"  ratio {k:<44} {v['median']:.2f}x median, {v['min']:.2f}x min", flush=True)
    info = B.fwid_alone[0][2]
    fmin = il[names[0]]["min_s"]
    prof["fwid_fit"] = dict(warm_s_table=fit_warm_s, warm_min_s_interleaved=fmin, **info,
                            ms_per_gauss_newton_step=1e3 * fmin / max(info["steps"], 1))
    ro = M.block(fit_one(*a1))
    prof["reference"] = dict(iterations=int(ro["iters"]), halvings=int(ro["halvings"]),
                             ms_per_iteration=1e3 * il[names[1]]["min_s"] / int(ro["iters"]))

    kw = B.fit_defaults

    def build(label, **over):
        fn = functools.partial(_oe._fit_batch, sm, n_local_batch=0, **{**kw, **over})
        compiled, tl, tc = M.aot(fn, *fb_args)
        out = M.block(compiled(*fb_args))
        th = out["theta"] if "theta" in out else out["s"] * np.asarray(fb_args[1])
        r = dict(trace_lower_s=tl, compile_s=tc, passes=int(out["passes"]),
                 steps=int(out["steps"]),
                 max_rel_diff_vs_fwid_fit=float(np.max(np.abs(th / B.fwid_alone[0][0] - 1))))
        print(f"  what-if {label:<40} trace+lower {tl:5.2f} s compile {tc:5.2f} s  steps "
              f"{r['steps']:4d} (R relaxations {r['passes']})  "
              f"drel {r['max_rel_diff_vs_fwid_fit']:.1e}", flush=True)
        return compiled, r

    def scan_simulate(model, exp, params=None, *, x0=None):
        params = model.params if params is None else params
        x0 = exp.x0 if x0 is None else x0
        xs = rk4_scan(model.f, params, x0, exp.u, exp.t[1] - exp.t[0], exp.consts)
        return xs, xs

    def scan_sensitivities(model, exp, params_of, theta):
        def ys(th):
            return rk4_scan(model.f, params_of(th), exp.x0, exp.u, exp.t[1] - exp.t[0],
                            exp.consts)
        return ys(theta), jax.jacfwd(ys)(theta)

    variants = {}
    orig_sim = _oe.simulate
    orig_sens = getattr(_oe, "simulate_sensitivities", None)
    try:  # the patches matter while tracing only; the compiled programs keep what they saw
        variants["as is"] = build("as is")
        _oe.simulate = scan_simulate
        if orig_sens is not None:
            _oe.simulate_sensitivities = scan_sensitivities
        variants["lax.scan RK4 (jacfwd) instead of diffrax"] = build(
            "lax.scan RK4 (jacfwd) instead of diffrax")
    finally:
        _oe.simulate = orig_sim
        if orig_sens is not None:
            _oe.simulate_sensitivities = orig_sens
    # timed round-robin, with the hand-written reference as the yardstick
    wt = {k: [] for k in variants}
    wt["JAX reference (jit)"] = []
    for _ in range(15):
        for k, (compiled, _) in variants.items():
            t0 = time.perf_counter()
            M.block(compiled(*fb_args))
            wt[k].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        M.block(fit_one(*a1))
        wt["JAX reference (jit)"].append(time.perf_counter() - t0)
    ref_min, ref_med = min(wt["JAX reference (jit)"]), statistics.median(wt["JAX reference (jit)"])
    wi = {}
    for k, (_, r) in variants.items():
        r.update(warm_s=statistics.median(wt[k]), warm_min_s=min(wt[k]), all_s=wt[k],
                 vs_reference_median=statistics.median(wt[k]) / ref_med,
                 vs_reference_min=min(wt[k]) / ref_min)
        wi[k] = r
        print(f"  what-if {k:<52} warm {r['warm_s']:.3f} s (min {r['warm_min_s']:.3f}) = "
              f"{r['vs_reference_median']:.2f}x / {r['vs_reference_min']:.2f}x the reference "
              f"(median / min)", flush=True)
    wi["JAX reference (jit)"] = dict(warm_s=ref_med, warm_min_s=ref_min,
                                     all_s=wt["JAX reference (jit)"])
    prof["what_if"] = wi
    prof["note"] = ("what-ifs compile fwid's own _fit_batch (as fwid.fit calls it for one "
                    "flight) with names in fwid.estimate._output_error patched in this process "
                    "only (simulate / simulate_sensitivities -> a lax.scan RK4 with jacfwd); "
                    "fwid's files are unchanged")
    return prof


def markdown_lines(prof):
    """The profile as Markdown lines (a section of speed.md, or profile.md)."""
    lines = ["", "## Profile (one flight)", "", "| part | run median (min) [ms] | "
             "trace+lower [s] | compile [s] |", "|---|---:|---:|---:|"]
    for k, v in prof["micro"].items():
        if isinstance(v, dict):
            lines.append(f"| {k} | {v['run_ms']:.3f} ({v['run_min_ms']:.3f}) | "
                         f"{v['trace_lower_s']:.2f} | {v['compile_s']:.2f} |")
    il = prof["interleaved"]
    lines += ["", "Interleaved timings (15 rounds, round-robin, so all see the same load):", "",
              "| call | median [s] | min [s] |", "|---|---:|---:|"]
    for k, v in il.items():
        if k != "ratios":
            lines.append(f"| {k} | {v['median_s']:.4f} | {v['min_s']:.4f} |")
    lines += [""] + [f"- {k}: {v['median']:.2f}x (median), {v['min']:.2f}x (min)"
                     for k, v in il["ratios"].items()]
    ff = prof["fwid_fit"]
    rf = prof["reference"]
    lines += ["", f"fwid.fit on flight 0: {ff['passes']} R relaxations, {ff['steps']} "
              f"Gauss-Newton steps, {ff['ms_per_gauss_newton_step']:.1f} ms per step (from "
              f"the minimum time). JAX reference: {rf['iterations']} iterations "
              f"({rf['halvings']} halvings), {rf['ms_per_iteration']:.1f} ms per iteration.",
              "",
              "What-ifs (" + prof["note"] + "):", "",
              "| variant | warm median (min) [s] | x reference (median / min) | "
              "trace+lower [s] | compile [s] | GN steps | R relaxations | "
              "rel diff vs fwid.fit |", "|---|---:|---:|---:|---:|---:|---|---:|"]
    for k, v in prof["what_if"].items():
        if "steps" not in v:
            lines.append(f"| {k} | {v['warm_s']:.4f} ({v['warm_min_s']:.4f}) | 1 | | | | | |")
            continue
        pp = v.get("passes", "")
        lines.append(f"| {k} | {v['warm_s']:.3f} ({v['warm_min_s']:.3f}) | "
                     f"{v['vs_reference_median']:.2f} / {v['vs_reference_min']:.2f} | "
                     f"{v['trace_lower_s']:.2f} | {v['compile_s']:.2f} | {v['steps']} | {pp} | "
                     f"{v['max_rel_diff_vs_fwid_fit']:.1e} |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "results" / "profile.json"))
    ap.add_argument("--start", choices=("true1.2", "least-squares"), default="true1.2",
                    help="start values: true x 1.2, or fwid's least-squares start per flight")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    F, starts, problem = setup(N_FLIGHTS, args.seed, args.start)
    B = Bench(F, starts)
    M.print_backend()
    prof = run_profile(B)
    res = dict(machine=M.machine(load0), problem=dict(**problem, **B.settings()), profile=prof,
               total_wall_s=time.perf_counter() - t_start)
    lines = ["# Where fwid's time goes", "", M.machine_line(res["machine"], "profile_fit.py"),
             f"Total {res['total_wall_s']:.0f} s."]
    M.write(res, args.out, "\n".join(lines + markdown_lines(prof)) + "\n")


if __name__ == "__main__":
    main()
