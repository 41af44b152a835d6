"""Speed benchmark: fwid's output-error fit against a scipy baseline and a hand-written JAX loop.

    python benchmarks/speed.py --out benchmarks/results/speed.json [--sizes 1,4,16,64,256]
                               [--quick] [--profile]
    python benchmarks/speed.py --process [1,16,64]   # the whole process: fwid identify
    python benchmarks/speed.py --stages [1,64]       # fit_each by stage, parallel in time

The same fits, in the same run, by three methods (set up in `benchmarks/_shared.py`):

1. **fwid**: `fwid.fit` on one flight; for N flights, N *independent* fits in one batched
   call, `fwid.fit_each`. Where fwid has no `fit_each` (older versions), or the flights start
   from different values (`--start least-squares`), the benchmark vmaps fwid's internal pure
   estimator `fwid.estimate._output_error._fit_batch` over a leading flight axis instead (each
   flight a batch of one, fwid.fit's default settings read from its signature). The batched
   estimates are checked against `fwid.fit` on each flight alone (rows "fwid.fit loop";
   identical means within 1e-9 relative).
2. **scipy**: `benchmarks/peers/scipy_output_error.py` (numpy RK4 + `scipy.optimize.least_squares`, finite
   differences), a Python loop over flights. Only a subset of flights is timed; for larger N
   the time is the measured mean per flight times N, marked *extrapolated*.
3. **JAX reference**: `benchmarks/peers/jax_output_error.py` (`lax.scan` RK4, jacfwd, hand-written
   Gauss-Newton with step halving, R relaxed every iteration), `vmap` for batches: the
   practical speed limit of the problem in JAX.

Problem (`benchmarks/cases/delfly_speed.py`): simulated DelFly longitudinal flights (Eq. 7 with the
four bias terms, 16 free parameters), 4.5 s at 200 Hz (900 samples), elevator 3211 (even
flights) or doublet (odd flights), white Gaussian measurement noise on all four states; every
method starts from the same values (true x 1.2 by default). Flight i is the same at every
size.

Reported per method and size: warm wall time (median of repeats after a warm-up), compile
time (first call minus warm), fits per second, speed-up over scipy, peak memory (tracemalloc
for scipy; for JAX the compiled program's XLA buffers, the growth of the process's peak RSS,
and on GPU the device's peak bytes), and the largest relative difference of the 12 aero
parameters from fwid (and in Cramer-Rao standard deviations). `--profile` adds where fwid's
time goes (simulation and Jacobian through diffrax vs a scan, Gauss-Newton steps per
relaxation pass, accepted vs rejected) and a few what-if timings made by patching fwid's
internals *in this process only* (fwid's files are not touched): that is
`benchmarks/profile_fit.py`, which also runs on its own.

`--quick` (sizes 1 and 4, fewer repeats, one scipy fit) is meant to finish in under three
minutes on a 2-core CPU. The machine is recorded in the JSON; on a GPU everything JAX runs
there unchanged (`jax.default_backend()`), scipy on the host CPU.
"""

from __future__ import annotations

import argparse
import functools
import os
import statistics
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))  # the fwid of this checkout, not another installed one

from cases.delfly_speed import setup  # noqa: E402  (first: imports fwid, float64 on)

from _shared import (  # noqa: E402
    block,
    interleaved,
    machine,
    machine_line,
    print_backend,
    time_calls,
    write,
    xla_memory,
)
from _shared import Bench, agreement  # noqa: E402
from profile_fit import markdown_lines as profile_lines  # noqa: E402
from profile_fit import run_profile  # noqa: E402


def run(args):
    sizes = sorted({1} | {int(s) for s in args.sizes.split(",")})  # N=1 is every ratio's base
    n_max = max(sizes)
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    F, starts, problem = setup(n_max, args.seed, args.start)
    B = Bench(F, starts)
    print_backend()
    rows = []
    fwid_est = {}  # n -> (theta (n,16), std (n,16)) from the fwid row of that size
    log = functools.partial(print, flush=True)

    def row(method, n, warm, first=None, **kw):
        w = statistics.median(warm) if warm else None
        r = dict(method=method, n_flights=n, warm_s=w, warm_min_s=min(warm) if warm else None,
                 warm_all_s=list(warm),
                 first_call_s=first,
                 compile_s=(None if first is None or w is None else max(first - w, 0.0)),
                 fits_per_s=(n / w if w else None), **kw)
        rows.append(r)
        log(f"  {method:<28} N={n:<4} warm {w:9.4f} s"
            + (f"  first {first:8.2f} s" if first is not None else ""))
        return r

    # ---- fwid.fit on single flights (N=1 row; the loop rows; the identity reference) ----
    log("fwid.fit (one flight per call)")
    _, first, warm, mem = time_calls(lambda: B.fwid_fit(0), args.fwid_repeats)
    th0, sd0, info0 = B.fwid_alone[0]
    row("fwid.fit", 1, warm, first, memory=dict(**mem, xla=B.fwid_fit_xla_memory(0)),
        fwid_info=info0, extrapolated=False)
    fwid_est[1] = (th0[None], sd0[None])
    n_loop = min(args.loop_flights, n_max)
    loop_t = [statistics.median(warm)]
    for i in range(1, n_loop):
        t0 = time.perf_counter()
        B.fwid_fit(i)
        loop_t.append(time.perf_counter() - t0)
    for n in sizes:
        if n == 1:
            continue
        k = min(n, n_loop)
        total = sum(loop_t[:k]) if k == n else statistics.mean(loop_t) * n
        row("fwid.fit loop", n, [total], None, extrapolated=k < n, measured_flights=k,
            fwid_info=[B.fwid_alone[i][2] for i in range(k)])

    # ---- fwid, N independent fits in one batched call ----
    log(f"fwid batched: {B.batched_label}" + ("" if B.use_fit_each else
        " (fwid.fit_each missing, or flights start from different values)"))
    for n in sizes:
        if n == 1 and args.quick:
            continue  # quick: N=1 is fwid.fit's row (saves one compilation)
        (theta, std, info), first, warm, mem = time_calls(B.fwid_batched(n),
                                                          args.fwid_batch_repeats)
        alone = [i for i in range(n) if i in B.fwid_alone]
        ident = None
        if alone:
            ta = np.stack([B.fwid_alone[i][0] for i in alone])
            ident = dict(flights_checked=len(alone),
                         max_rel_diff_all16=float(np.max(np.abs(theta[alone] - ta) / np.abs(ta))))
            ident["identical_1e-9"] = ident["max_rel_diff_all16"] <= 1e-9
        row(B.batched_label, n, warm, first,
            memory=dict(**mem, xla=B.fwid_batched_xla_memory(n)),
            identity_vs_fwid_fit_alone=ident, extrapolated=False, fwid_info=info)
        if n > 1 or 1 not in fwid_est:
            fwid_est[n] = (theta, std)

    # ---- JAX reference ----
    log("JAX reference (lax.scan RK4 + hand-written Gauss-Newton)")
    fit_one, fit_many = B.ref
    a1 = B.ref_args_one()
    out, first, warm, mem = time_calls(lambda: block(fit_one(*a1)), args.ref_repeats)
    r = row("JAX reference (jit)", 1, warm, first,
            memory=dict(**mem, xla=xla_memory(fit_one.lower(*a1).compile())),
            ref_info=dict(iters=int(out["iters"]), halvings=int(out["halvings"]),
                          converged=bool(out["converged"])), extrapolated=False)
    r["agreement"] = agreement(out["theta"][None], *fwid_est[1])
    for n in sizes:
        if n == 1 and args.quick:
            continue  # quick: N=1 is the jitted row
        a = B.ref_args(n)
        out, first, warm, mem = time_calls(lambda a=a: block(fit_many(*a)), args.ref_repeats)
        r = row("JAX reference (vmap)", n, warm, first,
                memory=dict(**mem, xla=xla_memory(fit_many.lower(*a).compile())),
                ref_info=dict(iters=out["iters"].tolist(), halvings=out["halvings"].tolist(),
                              all_converged=bool(out["converged"].all())), extrapolated=False)
        if n in fwid_est:
            r["agreement"] = agreement(out["theta"], *fwid_est[n])

    # ---- scipy baseline (a Python loop over flights) ----
    log("scipy baseline (numpy RK4 + least_squares, finite differences)")
    n_sc = min(args.scipy_flights, n_max)
    sc_times, sc_theta, sc_info = [], [], []
    for i in range(n_sc):
        reps = args.scipy_repeats if i == 0 else 1
        ts = []
        for _ in range(reps):
            t0 = time.perf_counter()
            res = B.scipy_fit(i)
            ts.append(time.perf_counter() - t0)
        sc_times.append(statistics.median(ts))
        if i == 0:
            ts0 = ts
        sc_theta.append(res["theta"])
        sc_info.append(dict(relaxations=res["n_iter"], simulations=res["n_fev"],
                            converged=bool(res["converged"])))
        log(f"    flight {i}: {sc_times[-1]:.2f} s ({res['n_iter']} relaxations, "
            f"{res['n_fev']} simulations)")
    # tracemalloc slows Python down: a separate, untimed run (quick: the first relaxation
    # pass only, which allocates the same arrays as every later pass)
    tracemalloc.start()
    B.scipy_fit(0, max_outer=1 if args.quick else 50)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    sc_first_single = sc_times[0]
    scipy_time = {}
    for n in sizes:
        k = min(n, n_sc)
        if n == 1:
            total, warm_all = sc_first_single, ts0
        else:
            total = sum(sc_times[:k]) if k == n else statistics.mean(sc_times) * n
            warm_all = [total]
        r = row("scipy baseline", n, warm_all if n == 1 else [total], None,
                memory=dict(tracemalloc_peak_bytes=int(peak),
                            tracemalloc_scope="first relaxation pass" if args.quick
                            else "whole fit"),
                extrapolated=k < n, measured_flights=k, scipy_info=sc_info[:k])
        r["warm_s"] = total
        r["warm_min_s"] = min(ts0) * n if n == 1 else total
        r["fits_per_s"] = n / total
        scipy_time[n] = total
        if n in fwid_est:
            kk = min(k, n)
            r["agreement"] = agreement(np.stack(sc_theta[:kk]), fwid_est[n][0][:kk],
                                       fwid_est[n][1][:kk])
            r["agreement"]["flights_compared"] = kk
    for r in rows:
        r["speedup_vs_scipy"] = scipy_time[r["n_flights"]] / r["warm_s"]
        if r["method"].startswith("fwid") and "agreement" not in r:
            r["agreement"] = dict(max_rel_diff_aero=0.0, max_diff_in_std_aero=0.0,
                                  note="the fwid reference itself")

    # ---- the head-to-head, round-robin: both calls see the same load ----
    log(f"fwid.fit against the JAX reference (jit), {args.rounds} rounds round-robin")
    head_to_head = interleaved({"fwid.fit": lambda: B.fwid_fit(0),
                                "reference": lambda: block(fit_one(*a1))}, args.rounds)
    head_to_head["rounds"] = args.rounds
    head_to_head["ratio_median"] = (head_to_head["fwid.fit"]["median_s"]
                                    / head_to_head["reference"]["median_s"])
    head_to_head["ratio_min"] = (head_to_head["fwid.fit"]["min_s"]
                                 / head_to_head["reference"]["min_s"])

    profile = run_profile(B, rows[0]["warm_s"]) if args.profile else None
    problem = dict(**problem, sizes=sizes, **B.settings())
    return dict(machine=machine(load0), problem=problem, rows=rows, profile=profile,
                head_to_head=head_to_head,
                quick=args.quick, repeats=dict(fwid=args.fwid_repeats,
                                               fwid_batched=args.fwid_batch_repeats,
                                               ref=args.ref_repeats,
                                               scipy_single=args.scipy_repeats),
                total_wall_s=time.perf_counter() - t_start)


def _fmt_mem(r):
    m = r.get("memory") or {}
    if "tracemalloc_peak_bytes" in m:
        return f"{m['tracemalloc_peak_bytes'] / 2**20:.1f} MiB (tracemalloc)"
    parts = []
    if m.get("xla"):
        parts.append(f"{m['xla']['total'] / 2**20:.1f} MiB XLA")
    if "device_peak_growth_bytes" in m:
        parts.append(f"+{m['device_peak_growth_bytes'] / 2**20:.0f} MiB dev peak")
    if "rss_growth_mb" in m:
        parts.append(f"+{m['rss_growth_mb']:.0f} MiB RSS")
    return ", ".join(parts) if parts else "-"


def markdown(res):
    mc, pb = res["machine"], res["problem"]
    lines = [
        "# fwid speed benchmark",
        "",
        machine_line(mc, "speed.py"),
        f"Problem: {pb['model']}, {len(pb['free_parameters'])} free parameters, "
        f"{pb['samples']} samples ({pb['duration_s']:.1f} s at {1 / pb['dt']:.0f} Hz), "
        f"{pb['inputs']}, white noise; start: {pb['start']}. "
        f"{'Quick run. ' if res['quick'] else ''}Total {res['total_wall_s']:.0f} s.",
        "",
        "| method | N | warm median (min) [s] | compile [s] | fits/s | speed-up vs scipy | peak memory "
        "| aero max rel diff vs fwid (in CR std) | note |",
        "|---|---:|---:|---:|---:|---:|---|---|---|",
    ]
    for r in res["rows"]:
        ag = r.get("agreement") or {}
        agree = ("-" if not ag else "ref" if ag.get("note") else
                 f"{ag['max_rel_diff_aero']:.1e} ({ag['max_diff_in_std_aero']:.1e})")
        note = []
        if r.get("extrapolated"):
            note.append(f"**extrapolated** from {r['measured_flights']} measured flight(s)")
        elif r.get("measured_flights") is not None and r["method"] != "scipy baseline":
            note.append(f"{r['measured_flights']} flights measured")
        idt = r.get("identity_vs_fwid_fit_alone")
        if idt:
            note.append(f"vs fwid.fit alone ({idt['flights_checked']} flights): "
                        f"{idt['max_rel_diff_all16']:.1e} "
                        f"{'identical' if idt['identical_1e-9'] else '**NOT identical**'}")
        if r.get("fwid_info") and isinstance(r["fwid_info"], dict):
            fi = r["fwid_info"]
            if "steps" in fi and isinstance(fi["steps"], int):
                note.append(f"{fi['steps']} GN steps ({fi['passes']} R relaxations)")
            elif "steps" in fi:
                note.append(f"GN steps {min(fi['steps'])}-{max(fi['steps'])}")
        if r.get("ref_info"):
            it = r["ref_info"]["iters"]
            note.append(f"{it if isinstance(it, int) else f'{min(it)}-{max(it)}'} iterations")
        comp = "-" if r["compile_s"] is None else f"{r['compile_s']:.1f}"
        lines.append(
            f"| {r['method']} | {r['n_flights']} | {r['warm_s']:.3f} ({r['warm_min_s']:.3f}) | "
            f"{comp} | "
            f"{r['fits_per_s']:.3g} | {r['speedup_vs_scipy']:.3g} | {_fmt_mem(r)} | {agree} | "
            f"{'; '.join(note)} |")
    lines += [
        "",
        "warm: median of repeated calls after the first; compile: first call minus warm. "
        "fwid for N > 1: `fwid.fit_each` (one vmapped call), or `jax.vmap` over fwid's internal "
        "`_fit_batch` where fwid has no `fit_each`. Memory: XLA = temporaries + arguments + outputs of the compiled program; "
        "RSS = growth of the process's peak resident set during the calls (0 when an earlier "
        "step already reached it); scipy: tracemalloc peak of Python allocations.",
    ]
    rw = {(r["method"], r["n_flights"]): r for r in res["rows"]}
    f1, j1 = rw.get(("fwid.fit", 1)), rw.get(("JAX reference (jit)", 1))
    if f1 and j1:
        lines += ["", f"Targets: fwid.fit warm / hand-written JAX warm = "
                  f"{f1['warm_s'] / j1['warm_s']:.2f}x median, "
                  f"{f1['warm_min_s'] / j1['warm_min_s']:.2f}x min (target <= 2x); fwid.fit "
                  f"warm speed-up over scipy {f1['speedup_vs_scipy']:.0f}x (target >= 50x); "
                  f"fwid.fit compile {f1['compile_s']:.1f} s (target < 30 s)."]
    hh = res.get("head_to_head")
    if hh:
        lines += ["", f"Head to head, {hh['rounds']} rounds round-robin (both calls see the same "
                  f"load; the steadier ratio on a shared machine): fwid.fit "
                  f"{hh['fwid.fit']['median_s']:.4f} s median ({hh['fwid.fit']['min_s']:.4f} min), "
                  f"hand-written JAX {hh['reference']['median_s']:.4f} s "
                  f"({hh['reference']['min_s']:.4f}): **{hh['ratio_median']:.2f}x median, "
                  f"{hh['ratio_min']:.2f}x min** (target: within 2x in every run)."]
    lines += ["", "Batch scaling, warm time for N flights / warm time for 1 flight (fwid: the "
              "batched call over fwid.fit on one flight):", ""]
    by = {(r["method"], r["n_flights"]): r["warm_s"] for r in res["rows"]}
    batched = next((r["method"] for r in res["rows"]
                    if r["method"] in ("fwid.fit_each", "fwid vmap(_fit_batch)")), None)
    for name, one, many in [("fwid", ("fwid.fit", 1), batched),
                            ("fwid.fit loop", ("fwid.fit", 1), "fwid.fit loop"),
                            ("JAX reference", ("JAX reference (jit)", 1), "JAX reference (vmap)"),
                            ("scipy", ("scipy baseline", 1), "scipy baseline")]:
        parts = [f"N={n}: {by[(many, n)] / by[one]:.2f}x" for n in res["problem"]["sizes"]
                 if n > 1 and (many, n) in by and one in by]
        if parts:
            lines.append(f"- {name}: " + ", ".join(parts))
    if res.get("profile"):
        lines += profile_lines(res["profile"])
    return "\n".join(lines) + "\n"


def process_row(args):
    """`--process`: see `benchmarks/_shared.py` (whole process)."""
    from _shared import process_markdown, run_process

    load0 = os.getloadavg()
    res = run_process([int(n) for n in args.process.split(",")],
                      min(args.scipy_flights, 2), args.seed)
    res["machine"] = machine(load0)
    out = HERE / "results" / "speed_process.json"
    write(res, out, process_markdown(res, machine_line(res["machine"], "speed.py")))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "results" / "speed.json"))
    ap.add_argument("--sizes", default="1,4,16,64,256", help="numbers of flights")
    ap.add_argument("--quick", action="store_true",
                    help="sizes 1,4, fewer repeats, one scipy fit (< 3 min on 2 CPU cores)")
    ap.add_argument("--profile", action="store_true", help="also profile fwid's parts")
    ap.add_argument("--start", choices=("true1.2", "least-squares"), default="true1.2",
                    help="start values: true x 1.2, or fwid's least-squares start per flight")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=30,
                    help="rounds of the round-robin head-to-head of fwid.fit and the reference")
    ap.add_argument("--repeats", type=int, default=3, help="warm repeats (>= 3)")
    ap.add_argument("--scipy-flights", type=int, default=4,
                    help="flights the scipy loop is timed on (more are extrapolated)")
    ap.add_argument("--loop-flights", type=int, default=4,
                    help="flights fitted one by one with fwid.fit (identity check, loop rows)")
    ap.add_argument("--process", nargs="?", const="1,16,64", default=None, metavar="SIZES",
                    help="instead: the whole-process row, `fwid identify` from a shell on "
                    "SIZES flights (default 1,16,64), cold and warm compilation cache, against "
                    "scipy in the same run (benchmarks/_shared.py); writes "
                    "results/speed_process.json and .md")
    ap.add_argument("--stages", nargs="?", const="1,64", default=None, metavar="SIZES",
                    help="instead: fit_each by stage on SIZES flights (default 1,64) beside the "
                    "hand-written layouts, and parallel in time at 900 and 9000 samples "
                    "(benchmarks/stages.py); writes results/speed_stages.json and .md")
    args = ap.parse_args(argv)
    if args.process:
        return process_row(args)
    if args.stages:
        import stages
        return stages.main(["--sizes", args.stages])
    if args.quick:
        args.sizes = "1,4"
        args.fwid_repeats, args.fwid_batch_repeats, args.ref_repeats = 3, 1, 7
        args.scipy_repeats = 1
        args.scipy_flights = min(args.scipy_flights, 1)
    else:
        args.fwid_repeats = args.fwid_batch_repeats = args.repeats
        args.ref_repeats = max(args.repeats, 5)
        args.scipy_repeats = args.repeats
    res = run(args)
    write(res, args.out, markdown(res))


if __name__ == "__main__":
    main()
