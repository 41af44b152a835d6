"""Withheld-effect benchmark of `fwid.diagnose`.

For each axis, effect (the catalogue, `none`, and `turbulence`, which is outside the
catalogue), strength and seed: simulate 8 training and 8 test flights with the effect, delete
the sidecars (so neither trim nor label is available: the diagnosis sees only the CSV columns
it would see from an outside simulator), run `fwid.diagnose`, and score:

- the verdict against the injected effect (confusion matrix per strength);
- the false-alarm rate (a catalogue effect named for `none` or `turbulence`);
- gap closure on the test flights, `G = (RMS_before - RMS_after) / (RMS_before - RMS_true)`,
  in the band the verdict's effect acts in (cycle-averaged or flapping), for each load whose
  baseline error exceeds `RMS_true` by `MATERIAL` (10 %). `RMS_true`, the true model's error,
  is the baseline's held-out error on effect-free twins of the same flights (same seeds and
  noise, strength 0), where its structure is exactly right. The error of the exact loads
  (`X_true`, ... written by the simulator, same filtering) is recorded too;
- the wall time of each diagnosis.

    python benchmarks/diagnosis.py [--seeds 10] [--strengths 0.5 1 2] [--axes lon lat]
                                   [--workers 2] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import platform
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)

EFFECTS = ("none", "flap-coupling", "nonlinear-aero", "lon-lat-coupling", "actuator-dynamics",
           "turbulence")
LOADS = ("X", "Y", "Z", "L", "M", "N")


def _write(folder, n, axis, seed, effect, strength, **kw):
    """Write `n` blind flights (sidecars deleted) into `folder`; `kw` go to `write_flights`
    (form, vehicle, noise, duration, rate, input, ...)."""
    from fwid.synth import write_flights

    paths = write_flights(folder, n, axis, seed=seed, effect=effect, strength=strength,
                          truth_columns=True, **kw)
    for p in paths:
        p.with_suffix(".json").unlink()  # blind: no sidecar (trim, label)
    return paths


def _true_rms(flights, band):
    """RMS per load of (measured - exact) loads in `band`, after the diagnosis's own
    filtering: the true model's error (its trim load removed per flight, as the diagnosis
    re-estimates it)."""
    from fwid.diagnosis._signals import signals

    err = {ld: [] for ld in LOADS}
    for f in flights:
        s = signals(f)
        t = signals(f.with_columns(**{ld: f[f"{ld}_true"] for ld in LOADS}))
        for ld in LOADS:
            e = s.loads[band][ld] - t.loads[band][ld]
            err[ld].append(e - np.mean(e))
    return {ld: float(np.sqrt(np.mean(np.concatenate(v) ** 2))) for ld, v in err.items()}


#: A load counts as affected when the baseline's held-out error exceeds the true model's by
#: this fraction.
MATERIAL = 0.1


def run_case(case):
    import fwid

    axis, effect, strength, seed = case
    with tempfile.TemporaryDirectory() as d:
        _write(f"{d}/train", 8, axis, 1000 * seed, effect, strength)
        _write(f"{d}/test", 8, axis, 1000 * seed + 500, effect, strength)
        train = fwid.load_flights(f"{d}/train")
        test = fwid.load_flights(f"{d}/test")
        t0 = time.perf_counter()
        diag = fwid.diagnose(train, test, axis=axis)
        wall = time.perf_counter() - t0
        c = diag.candidates[0] if diag.verdict == "none" else diag.candidate(diag.verdict)
        floor = _true_rms(test, c["band"])
        if effect != "none" and diag.verdict != "none":
            # the true model's error: the baseline on effect-free twins of the same flights
            # (same seeds and noise, strength 0), for which its structure is exactly right
            _write(f"{d}/twin_train", 8, axis, 1000 * seed, effect, 0.0)
            _write(f"{d}/twin_test", 8, axis, 1000 * seed + 500, effect, 0.0)
            twin = fwid.diagnose(fwid.load_flights(f"{d}/twin_train"),
                                 fwid.load_flights(f"{d}/twin_test"), axis=axis)
            ref = {ld: v["before"] for ld, v in twin.candidate(c["effect"])["test_rms_in_band"].items()}
    out = {"axis": axis, "effect": effect, "strength": strength, "seed": seed,
           "verdict": diag.verdict, "wall_s": wall, "ranking": [c["effect"] for c in diag.candidates]}
    if diag.verdict != "none":
        out["shrink_pct"] = c["shrink_pct"]
        rb = c["test_rms_in_band"]
        if effect != "none":
            out["G"] = {ld: (v["before"] - v["after"]) / (v["before"] - ref[ld])
                        for ld, v in rb.items() if v["before"] > (1 + MATERIAL) * ref[ld]}
            out["in_band"] = {ld: {**v, "true_model": ref[ld], "exact_loads": floor[ld]}
                              for ld, v in rb.items()}
        out["affected"] = c["affected"]
    return out


def _summarise(results, strengths, axes):
    lines = []
    verdicts = ("none",) + EFFECTS[1:5]
    for axis in axes:
        for s in strengths:
            rows = [r for r in results if r["axis"] == axis and r["strength"] == s]
            if not rows:
                continue
            lines.append(f"\n### {axis}, strength {s:g}\n")
            lines.append("| injected \\ verdict | " + " | ".join(verdicts) + " | correct |")
            lines.append("|---|" + "---:|" * (len(verdicts) + 1))
            for e in EFFECTS:
                rr = [r for r in rows if r["effect"] == e]
                if not rr:
                    continue
                cnt = Counter(r["verdict"] for r in rr)
                want = "none" if e in ("none", "turbulence") else e
                lines.append(f"| {e} | " + " | ".join(str(cnt.get(v, 0)) for v in verdicts)
                             + f" | {cnt.get(want, 0)}/{len(rr)} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--strengths", type=float, nargs="+", default=[0.5, 1.0, 2.0])
    ap.add_argument("--axes", nargs="+", default=["lon", "lat"])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)

    cases = [(a, e, s, seed) for a in args.axes for s in args.strengths for e in EFFECTS
             for seed in range(args.seeds)]
    t0 = time.perf_counter()
    with mp.get_context("spawn").Pool(args.workers) as pool:
        results = []
        for i, r in enumerate(pool.imap_unordered(run_case, cases), 1):
            results.append(r)
            print(f"[{i}/{len(cases)}] {r['axis']} {r['effect']} s={r['strength']:g} "
                  f"seed={r['seed']}: {r['verdict']} ({r['wall_s']:.1f} s)", flush=True)
    total = time.perf_counter() - t0
    results.sort(key=lambda r: (r["axis"], r["strength"], EFFECTS.index(r["effect"]), r["seed"]))

    cat = [r for r in results if r["effect"] in EFFECTS[1:5]]
    null = [r for r in results if r["effect"] == "none"]
    ooc = [r for r in results if r["effect"] == "turbulence"]
    correct = [r for r in cat if r["verdict"] == r["effect"]]
    gs = [g for r in correct for g in r.get("G", {}).values()]
    summary = {
        "cases": len(results),
        "catalogue_correct": f"{len(correct)}/{len(cat)}",
        "catalogue_correct_by_strength": {
            f"{s:g}": f"{sum(r['verdict'] == r['effect'] for r in cat if r['strength'] == s)}/"
                      f"{sum(r['strength'] == s for r in cat)}" for s in args.strengths},
        "none_on_clean": f"{sum(r['verdict'] == 'none' for r in null)}/{len(null)}",
        "false_alarm_rate_clean": (sum(r["verdict"] != "none" for r in null) / len(null))
        if null else None,
        "out_of_catalogue_none": f"{sum(r['verdict'] == 'none' for r in ooc)}/{len(ooc)}",
        "wrong_named_effect": sum(r["verdict"] not in ("none", r["effect"]) for r in cat),
        "gap_closure_G": {"median": float(np.median(gs)) if gs else None,
                          "p10": float(np.percentile(gs, 10)) if gs else None,
                          "min": float(np.min(gs)) if gs else None,
                          "share_at_least_half": float(np.mean(np.array(gs) >= 0.5)) if gs else None},
        "wall_s_per_diagnosis": {"median": float(np.median([r["wall_s"] for r in results])),
                                 "max": float(np.max([r["wall_s"] for r in results]))},
        "total_s": total,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "diagnosis.json").write_text(_provenance.json_text({"summary": summary, "results": results},
                                                   indent=1))
    md = [
        "# fwid diagnose: withheld-effect benchmark",
        "",
        (f"Machine: {platform.platform()}, {mp.cpu_count()} CPUs; {args.workers} worker(s). "
        f"8 training + 8 test flights of 4.5 s at 200 Hz per case, sidecars deleted; "
        f"seeds {args.seeds}, strengths {args.strengths}, axes {args.axes}. Total {total:.0f} s."),
        "",
        "Command: `python benchmarks/diagnosis.py " + " ".join(sys.argv[1:] if argv is None else argv) + "`",
        "",
        "## Summary",
        "",
    ] + [f"- {k}: {v}" for k, v in summary.items()] + [
        "",
        ("G = (RMS before - RMS after) / (RMS before - RMS of the true model), on the test "
         "flights, in the band of the verdict's effect, per load whose baseline error exceeds "
         "the true model's by 10 %; the true model's error is the baseline's on effect-free "
         "twins of the same flights (same seeds and noise). For correct verdicts."),
        "",
        ("## Confusion matrices (rows: injected effect; `turbulence` is outside the catalogue, "
        "its correct answer is none)"),
        _summarise(results, args.strengths, args.axes),
    ]
    (out / "diagnosis.md").write_text(_provenance.markdown("\n".join(md) + "\n"))
    print("\n".join(md))


if __name__ == "__main__":
    main()
