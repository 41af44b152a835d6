"""Whole-process time of `fwid diagnose` (simulation block on) against `fwid identify` on the
same 16 flights, each as a second process on a warm compilation cache (target: at most 1.2x
on clean flights, 2.5x with a `nonlinear-aero` verdict).

`fwid simulate` writes 8 training and 8 test flights (`--effect`, default `none`; `--axis`);
then, from a shell as a user runs them, in turns so that both see the same load:

    fwid identify TRAIN TEST --model lon --out DIR          (the 16 flights)
    fwid diagnose --train TRAIN --test TEST --out DIR       (simulation block on)

The first run of each fills the persistent compilation cache and is reported apart; the
`--repeats` runs after it are timed (median). Each timed diagnosis's progress lines (stderr)
are kept, with the time each appeared, so the stages' share shows.

    python benchmarks/diagnosis_speed.py [--effect none] [--axis lon] [--repeats 2]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _provenance  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def _run(args: list[str]) -> dict:
    """`python -m fwid.cli ARGS` from this checkout; wall time, exit code, stderr lines with
    the second each appeared."""
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "fwid.cli", *args], cwd=ROOT,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = []
    for line in p.stderr:
        lines.append((round(time.perf_counter() - t0, 1), line.rstrip()))
    p.wait()
    return {"wall_s": time.perf_counter() - t0, "rc": p.returncode, "stderr": lines,
            "stdout_tail": p.stdout.read()[-400:]}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--effect", default="none")
    ap.add_argument("--axis", default="lon", choices=("lon", "lat"))
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", default=str(HERE / "results" / "diagnosis_speed"))
    args = ap.parse_args(argv)
    model = args.axis
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        for name, seed in (("train", 1), ("test", 2)):
            r = _run(["simulate", str(d / name), "--flights", "8", "--axis", args.axis,
                      "--effect", args.effect, "--seed", str(seed)])
            if r["rc"]:
                raise SystemExit(f"fwid simulate failed: {r['stderr'][-3:]}")
        ident = ["identify", str(d / "train"), str(d / "test"), "--model", model,
                 "--out", str(d / "id")]
        diag = ["diagnose", "--train", str(d / "train"), "--test", str(d / "test"),
                "--axis", args.axis, "--out", str(d / "diag")]
        runs = {"identify": [], "diagnose": []}
        for i in range(args.repeats + 1):  # run 0 fills the compilation cache
            for name, cmd in (("identify", ident), ("diagnose", diag)):
                r = _run(cmd)
                runs[name].append(r)
                print(f"{name} run {i}: {r['wall_s']:.1f} s, exit {r['rc']}", flush=True)
        verdict = json.loads((d / "diag" / "diagnosis.json").read_text())["verdict"] \
            if (d / "diag" / "diagnosis.json").exists() else None
    load1 = os.getloadavg()

    def med(name):
        w = sorted(r["wall_s"] for r in runs[name][1:])
        return w[len(w) // 2] if len(w) % 2 else 0.5 * (w[len(w) // 2 - 1] + w[len(w) // 2])

    ti, td = med("identify"), med("diagnose")
    res = {"effect": args.effect, "axis": args.axis, "repeats": args.repeats,
           "identify_s": ti, "diagnose_s": td, "ratio": td / ti, "verdict": verdict,
           "first_identify_s": runs["identify"][0]["wall_s"],
           "first_diagnose_s": runs["diagnose"][0]["wall_s"],
           "runs": {k: [{"wall_s": r["wall_s"], "rc": r["rc"]} for r in v]
                    for k, v in runs.items()},
           "diagnose_progress": runs["diagnose"][-1]["stderr"],
           "load_average": [load0[0], load1[0]]}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    prov = _provenance.provenance()  # once, before either file is written
    out.with_suffix(".json").write_text(_provenance.json_text(res, prov, indent=1))
    prog = "\n".join(f"    {t:6.1f} s  {line}" for t, line in res["diagnose_progress"])
    text = "\n".join([
        "# Whole process: `fwid diagnose` (simulation block) against `fwid identify`, "
        "8 + 8 flights", "",
        f"Flights: `fwid simulate --flights 8 --axis {args.axis} --effect {args.effect}` "
        "(seeds 1 and 2). Second and later processes on a warm compilation cache, in turns; "
        f"median of {args.repeats}. Load average {load0[0]:.1f} at start, {load1[0]:.1f} at end "
        "(2 CPUs, shared).", "",
        "| command | first process (cache filled) s | timed s (median) | exit codes |",
        "|---|---:|---:|---|",
        f"| `fwid identify TRAIN TEST --model {model}` (16 flights) | "
        f"{res['first_identify_s']:.1f} | {ti:.1f} | "
        f"{[r['rc'] for r in runs['identify']]} |",
        f"| `fwid diagnose --train TRAIN --test TEST` (simulation block on) | "
        f"{res['first_diagnose_s']:.1f} | {td:.1f} | "
        f"{[r['rc'] for r in runs['diagnose']]} |", "",
        f"**diagnose / identify: {td / ti:.2f}x** (target: at most 1.2x clean, 2.5x with an effect). "
        f"Verdict: `{verdict}`.", "",
        "Progress lines of the last timed diagnosis (seconds since its start):", "", prog, ""])
    out.with_suffix(".md").write_text(_provenance.markdown(text, prov))
    print(text)


if __name__ == "__main__":
    main()
