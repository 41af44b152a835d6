"""The diagnosis on raw tracking flights, end to end as a user runs it: `fwid simulate --raw`,
`fwid reconstruct`, `fwid diagnose` (target: a lagging actuator is named, a clean set is `none`).

Per seed, form (`motive`: a Motive export with its autopilot log and gyro; `fwid`: the fwid raw
CSV, no gyro) and effect (`none`, `actuator-dynamics`), 6 training flights (seed `s`) and 6
test flights (seed `s + 200`, prefix `test`):

    fwid simulate RAW_TRAIN --raw FORM --effect EFFECT --flights 6 --seed S
    fwid simulate RAW_TEST --raw FORM --effect EFFECT --flights 6 --seed S+200 --prefix test
    fwid reconstruct RAW_TRAIN [--body DelFly] --out TRAIN --no-figures
    fwid reconstruct RAW_TEST [--body DelFly] --out TEST --no-figures
    fwid diagnose --train TRAIN --test TEST --out DIAG [--no-simulation for none]

Right: the verdict is the injected effect (`none` for clean flights). Also recorded: the
confidence set, the simulated-state shrink (actuator) and each stage's wall time. The seeds
11-16 and 21-26 were looked at while the reconstruction was developed (`--half dev`: 21-26);
31-36 were not (`--half heldout`, the default, the one reported).

    python benchmarks/raw_diagnosis.py [--half heldout|dev] [--workers 1]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _provenance  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SEEDS = {"dev": (21, 22, 23, 24, 25, 26), "heldout": (31, 32, 33, 34, 35, 36)}
FORMS = ("motive", "fwid")
EFFECTS = ("none", "actuator-dynamics")


def _fwid(*args) -> float:
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "fwid.cli", *map(str, args)], cwd=ROOT,
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"fwid {' '.join(map(str, args))}: {p.stderr.strip()[-300:]}")
    return time.perf_counter() - t0


def one(seed: int, form: str, effect: str, work: Path) -> dict:
    d = work / f"{effect}-{form}-{seed}"
    body = ["--body", "DelFly"] if form == "motive" else []
    wall = {}
    wall["simulate"] = (_fwid("simulate", d / "raw_train", "--raw", form, "--effect", effect,
                              "--flights", 6, "--seed", seed)
                        + _fwid("simulate", d / "raw_test", "--raw", form, "--effect", effect,
                                "--flights", 6, "--seed", seed + 200, "--prefix", "test"))
    wall["reconstruct"] = sum(_fwid("reconstruct", d / f"raw_{p}", *body, "--out", d / p,
                                    "--no-figures", "--quiet") for p in ("train", "test"))
    sim = ["--no-simulation"] if effect == "none" else []
    wall["diagnose"] = _fwid("diagnose", "--train", d / "train", "--test", d / "test",
                             "--out", d / "diag", "--quiet", *sim)
    res = json.loads((d / "diag" / "diagnosis.json").read_text())
    return {"seed": seed, "form": form, "effect": effect, "verdict": res["verdict"],
            "right": res["verdict"] == effect,
            "confidence_set": [x["explanation"] for x in res.get("confidence_set", [])],
            "simulated_shrink_pct": (res.get("simulation") or {}).get("shrink_pct"),
            "wall_s": {k: round(v, 1) for k, v in wall.items()}}


def summary(rows: list[dict], half: str) -> str:
    lines = [f"# Diagnosis on raw tracking flights ({half} seeds)", "",
             "`fwid simulate --raw` -> `fwid reconstruct` -> `fwid diagnose`, 6 + 6 flights; see "
             "the script's docstring. Right: the verdict is the injected effect.", "",
             "| form | effect | right | verdicts | confidence sets | simulated shrink % |",
             "|---|---|---:|---|---|---|"]
    for form in FORMS:
        for eff in EFFECTS:
            rs = [r for r in rows if r["form"] == form and r["effect"] == eff]
            if not rs:
                continue
            sets = "; ".join("{" + ", ".join("+".join(e) or "none" for e in r["confidence_set"]) + "}"
                             for r in rs)
            shr = ", ".join(f"{r['simulated_shrink_pct']:.0f}" for r in rs
                            if r["simulated_shrink_pct"] is not None) or "-"
            lines.append(f"| {form} | {eff} | {sum(r['right'] for r in rs)}/{len(rs)} | "
                         f"{', '.join(r['verdict'] or 'error' for r in rs)} | {sets} | {shr} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--half", choices=tuple(SEEDS), default="heldout")
    ap.add_argument("--workers", type=int, default=1, help="cases run at once")
    ap.add_argument("--out", type=Path, default=None,
                    help="results file stem (default benchmarks/results/raw_diagnosis_HALF)")
    args = ap.parse_args(argv)
    out = args.out or HERE / "results" / f"raw_diagnosis_{args.half}"
    prov = _provenance.provenance()
    cases = [(s, f, e) for s in SEEDS[args.half] for f in FORMS for e in EFFECTS]
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(args.workers) as pool:
        futures = [pool.submit(one, s, f, e, Path(tmp)) for s, f, e in cases]
        rows = []
        for (s, f, e), fut in zip(cases, futures):
            try:
                rows.append(fut.result())
            except RuntimeError as err:
                rows.append({"seed": s, "form": f, "effect": e, "verdict": None, "right": False,
                             "confidence_set": [], "simulated_shrink_pct": None,
                             "error": str(err)})
            r = rows[-1]
            print(f"{s} {f} {e}: {r['verdict']} {r['confidence_set']}", file=sys.stderr, flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(_provenance.json_text({"cases": rows}, prov, indent=1))
    out.with_suffix(".md").write_text(_provenance.markdown(summary(rows, args.half), prov))
    print(summary(rows, args.half))


if __name__ == "__main__":
    os.environ.setdefault("PYTHONWARNINGS", "ignore")
    main()
