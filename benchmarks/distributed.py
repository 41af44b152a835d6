"""Benchmark: `fwid.fit_each` on N flights in one process against two local processes
(`fwid.initialize_distributed`, gloo CPU collectives over 127.0.0.1), in the same run.

    python benchmarks/distributed.py [--flights 16] [--repeats 3]
                                     [--out benchmarks/results/distributed.json]

Three layouts, each a fresh set of processes (compilation cache off, `FWID_JAX_CACHE=0`):
one process with one CPU device, one process with two (fwid's default on 2 cores: one global
`shard_map` over both), and two processes with one device each (the same `shard_map` over a
global mesh of two devices, one per process), free to use every core or each pinned to a core
of its own (`os.sched_setaffinity`, as a cluster gives each process its own cores). Every process builds the same flights
(`cases/delfly_speed.py`, the speed benchmark's, least-squares start as `fit_each` does by default)
and calls `fit_each`; the first call (compile + fit) and the median of `--repeats` warm calls
are timed on process 0 (every call is collective across the processes), and of the last warm
call the part spent in the least-squares starts (computed by every process for all flights)
and in the batched fit (spread over the devices, all-gather included). The estimates of
every layout are compared with the first (largest relative difference).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
LAYOUTS = ((1, 1, 0), (1, 2, 0), (2, 1, 0), (2, 1, 1))  # (processes, devices, pinned)


def worker(pid: int, nproc: int, port: int, devices: int, pinned: int, n: int, repeats: int,
           out: str) -> None:
    """One process of a layout: fit `n` flights, time them, process 0 writes `out` (JSON).
    `pinned`: this process runs on one core of its own (before JAX sizes its threads)."""
    if pinned:
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[pid % len(cores)]})
    os.environ["FWID_CPU_DEVICES"] = str(devices)
    import fwid

    if nproc > 1:
        fwid.initialize_distributed(f"127.0.0.1:{port}", nproc, pid, local_devices=devices)
    sys.path.insert(0, str(HERE))
    import jax
    from cases.delfly_speed import experiment, make_flights, vehicle_constants

    consts, _ = vehicle_constants()
    F = make_flights(n, 0, consts)
    exps = [experiment(F, i) for i in range(n)]
    model = fwid.longitudinal()
    spent = _timed_parts()
    t0 = time.perf_counter()
    results = fwid.fit_each(model, exps)
    first = time.perf_counter() - t0
    warm = []
    for _ in range(repeats):
        spent.clear()
        t0 = time.perf_counter()
        fwid.fit_each(model, exps)
        warm.append(time.perf_counter() - t0)
    if pid == 0:
        Path(out).write_text(json.dumps(dict(
            processes=nproc, devices_per_process=devices, pinned=pinned, global_devices=len(jax.devices()),
            first_s=first, warm_s=warm, last_warm_parts_s=dict(spent), theta=[np.asarray(r.theta).tolist() for r in results],
            converged=sum(bool(r.converged) for r in results))))


def _timed_parts() -> dict:
    """Time the least-squares starts and the batched fit (all-gather included) inside
    `fit_each`, by wrapping fwid's internals in this process only; returns the seconds
    spent in each, by name, since the last `clear()`."""
    import fwid.estimate._each as each

    spent: dict = {}

    def timed(name, fn):
        def call(*a, **kw):
            t0 = time.perf_counter()
            out = fn(*a, **kw)
            spent[name] = spent.get(name, 0.0) + time.perf_counter() - t0
            return out
        return call

    each.least_squares_start_each = timed("starts", each.least_squares_start_each)
    each._run_batched = timed("batched fit", each._run_batched)
    return spent


def layout(nproc: int, devices: int, pinned: int, n: int, repeats: int, tmp: Path) -> dict:
    """Run one layout as `nproc` fresh processes; process 0's record."""
    sys.path.insert(0, str(ROOT))
    from tests.estimate._distributed_worker import free_port

    out, port = tmp / f"p{nproc}d{devices}c{pinned}.json", free_port()
    env = dict(os.environ, PYTHONPATH=str(ROOT), FWID_JAX_CACHE="0")
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, __file__, "--worker", str(pid), str(nproc),
                               str(port), str(devices), str(pinned), str(n), str(repeats),
                               str(out)],
                              cwd=ROOT, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True) for pid in range(nproc)]
    logs = [p.communicate(timeout=900)[0] for p in procs]
    if any(p.returncode for p in procs):
        raise RuntimeError("\n".join(log[-3000:] for log in logs))
    rec = json.loads(out.read_text())
    rec["process_wall_s"] = time.perf_counter() - t0
    return rec


def _label(r: dict) -> str:
    return (f"{r['processes']} x {r['devices_per_process']}"
            + (", one core each" if r["pinned"] else ""))


def markdown(recs: list[dict], n: int, load: tuple) -> str:
    base = recs[0]
    th0 = np.array(base["theta"])
    lines = [
        "# fit_each over processes: one process against two (jax.distributed)", "",
        f"`python benchmarks/distributed.py --flights {n}`: {n} simulated longitudinal flights "
        "(`benchmarks/cases/delfly_speed.py`, 4.5 s at 200 Hz, least-squares start), "
        f"{os.cpu_count()} CPUs, load average {load[0]:.1f} at start, "
        f"{os.getloadavg()[0]:.1f} at end. "
        "All layouts in the same run, each in fresh processes with the compilation cache off. "
        "**The machine is a shared 2-core one: absolute times are noisy, read the ratios.**", "",
        "| processes x CPU devices | first call (compile + fit) | warm `fit_each` (median) "
        "| flights/s (warm) | vs 1 x 1 | whole run (processes) | converged "
        "| of which starts / batched fit (last warm call) "
        "| max rel. diff of estimates vs 1 x 1 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    w0 = statistics.median(base["warm_s"])
    for r in recs:
        w = statistics.median(r["warm_s"])
        th, parts = np.array(r["theta"]), r["last_warm_parts_s"]
        diff = float(np.max(np.abs(th - th0) / np.maximum(np.abs(th0), 1e-300)))
        lines.append(
            f"| {_label(r)} | {r['first_s']:.2f} s "
            f"| {w:.3f} s | {n / w:.1f} | {w0 / w:.2f}x | {r['process_wall_s']:.1f} s "
            f"| {r['converged']}/{n} | {parts['starts']:.3f} s / {parts['batched fit']:.3f} s "
            f"| {diff:.1e} |")
    lines += ["", "Warm times (s), every repeat: " + "; ".join(
        f"{_label(r)}: " + ", ".join(f"{t:.3f}" for t in r["warm_s"]) for r in recs), ""]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--flights", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "distributed.json"))
    ap.add_argument("--worker", nargs=8, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        w = args.worker
        worker(*map(int, w[:7]), w[7])
        return
    load = os.getloadavg()
    tmp = Path(args.out).parent / ".distributed_tmp"
    tmp.mkdir(parents=True, exist_ok=True)
    recs = []
    for nproc, devices, pinned in LAYOUTS:
        print(f"{nproc} process(es) x {devices} device(s), pinned={pinned} ...", flush=True)
        recs.append(layout(nproc, devices, pinned, args.flights, args.repeats, tmp))
    for f in tmp.iterdir():
        f.unlink()
    tmp.rmdir()
    md = markdown(recs, args.flights, load)
    Path(args.out).write_text(_provenance.json_text(recs, indent=1))
    Path(args.out).with_suffix(".md").write_text(_provenance.markdown(md))
    print(md)


if __name__ == "__main__":
    main()
