"""The whole-process row of `speed.py` (`--process`): `fwid identify FOLDER --model lon --out
DIR` as a user runs it from a shell, on 1, 16 and 64 simulated flights, cold (an empty
compilation cache folder) and warm (a second process on the same folder), against the scipy
baseline (numpy RK4 + `scipy.optimize.least_squares`, `_baseline.py`) timed in the same run,
with where the time goes (`_cli_timed.py`: import, compile, fit, figures, reports).

The scipy time for N flights is its measured mean per fit on the benchmark problem's flights
(`_problem.py`, same model, length and step as `fwid simulate`'s) times N, marked
extrapolated beyond the flights timed; it counts no process start-up, no reading of the
files and no report (in scipy's favour).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
PARTS = ("import", "compile", "fit", "figures", "reports")


def cli_process(folder: Path, out: Path, cache: Path, figures: str = "summary") -> dict:
    """One `fwid identify` process, timed from outside, with its breakdown."""
    env = {**os.environ, "FWID_JAX_CACHE": str(cache)}
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(HERE / "_cli_timed.py"), "identify", str(folder),
                           "--model", "lon", "--out", str(out), "--quiet", "--figures", figures],
                          env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"fwid identify failed: {proc.stderr[-2000:]}")
    parts = json.loads(proc.stdout.strip().splitlines()[-1])
    parts["other"] = wall - sum(parts[k] for k in PARTS)
    return {"wall_s": wall, **parts}


def scipy_per_fit(n_fits: int, seed: int) -> dict:
    """The scipy baseline's mean time per flight, over `n_fits` flights of the problem."""
    from _methods import Bench
    from _problem import setup

    F, starts, _ = setup(n_fits, seed, "true1.2")
    bench = Bench(F, starts)
    times = []
    for i in range(n_fits):
        t0 = time.perf_counter()
        bench.scipy_fit(i)
        times.append(time.perf_counter() - t0)
    return {"per_fit_s": sum(times) / len(times), "fits_timed": n_fits, "times_s": times}


def run(sizes, scipy_fits: int, seed: int) -> dict:
    from fwid.synth import write_flights

    rows = []
    with tempfile.TemporaryDirectory(prefix="fwid-process-") as tmp:
        tmp = Path(tmp)
        for n in sizes:
            folder = tmp / f"flights_{n}"
            write_flights(folder, n_flights=n, axis="lon", seed=seed)
            cache = tmp / f"cache_{n}"  # empty: cold
            for state in ("cold", "warm"):
                r = cli_process(folder, tmp / f"out_{n}_{state}", cache)
                rows.append({"flights": n, "cache": state, **r})
                print(f"fwid identify, {n} flights, {state}: {r['wall_s']:.1f} s "
                      f"({', '.join(f'{k} {r[k]:.1f}' for k in (*PARTS, 'other'))}; "
                      f"{r['compiles']} compilations)", flush=True)
    scipy = scipy_per_fit(scipy_fits, seed)
    print(f"scipy baseline: {scipy['per_fit_s']:.1f} s a fit ({scipy_fits} timed)", flush=True)
    for r in rows:
        r["scipy_s"] = scipy["per_fit_s"] * r["flights"]
        r["scipy_extrapolated"] = r["flights"] > scipy_fits
        r["speedup_vs_scipy"] = r["scipy_s"] / r["wall_s"]
    return {"rows": rows, "scipy": scipy}


def markdown(res, machine_line: str) -> str:
    lines = ["# Whole process: `fwid identify FOLDER --model lon --out DIR` from a shell", "",
             machine_line, "",
             "Cold: an empty compilation cache folder; warm: a second process on it. "
             "Seconds; the parts from `benchmarks/_cli_timed.py` (compile: tracing, lowering, "
             "XLA compilation or cache loading; other: the interpreter, reading the flights and "
             "the rest; the tracing of nested jits overlaps, so compile is an upper bound and "
             "fit a lower one). "
             "scipy: numpy RK4 + `least_squares`, its mean time per fit in this run times the "
             "flights (* extrapolated), without process start-up or reports.", "",
             "| flights | cache | whole process | import | compile | fit | figures | reports "
             "| other | XLA compilations | scipy | fwid faster by |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in res["rows"]:
        star = "*" if r["scipy_extrapolated"] else ""
        lines.append(
            f"| {r['flights']} | {r['cache']} | {r['wall_s']:.1f} | "
            + " | ".join(f"{r[k]:.1f}" for k in (*PARTS, "other"))
            + f" | {r['compiles']} | {r['scipy_s']:.0f}{star} | {r['speedup_vs_scipy']:.1f}x |")
    return "\n".join(lines) + "\n"
