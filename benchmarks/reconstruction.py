"""How well and how fast `fwid reconstruct` turns raw recordings into flight data:
the error against the simulator's exact states and loads, per band, and the whole process
on 16 takes of 60 s; beside it, what a Python user writes instead (`peers/finite_differences.py`).

    python benchmarks/reconstruction.py [--quick] [--no-speed] [--out benchmarks/results/reconstruction.json]

**Takes.** `fwid simulate --raw` flights (the 6-DOF nonlinear DelFly, `fwid.synth.write_raw_flights`,
longitudinal 3211/doublet/211/pulse inputs), recorded around the default (Motive export in
y-up mm, 200 Hz, 0.4 mm and 0.15 deg pose noise, 0.5 % dropouts, autopilot log at 512 Hz on a
clock offset by a random -200..200 s), varying one factor at a time: pose noise 0.1-2 mm
(attitude noise in proportion), tracking rate 100-500 Hz, dropout share 0-5 %, the clock
offset; plus the fwid raw CSV (NED, one file, sign-flipping quaternions), and takes of 30 s,
60 s and 90 s (a manoeuvre in the first seconds, then steady flight; real takes run 75-90 s),
the last also as a fwid raw CSV (no gyro). `--only TEXT` runs the cases whose name holds
TEXT (e.g. `--only "90 s" --no-speed`) and writes a results file only where `--out` is given.

**Errors** (`error`): over the overlap of take and log less 0.5 s at each end, against
`truth/NAME.csv` on the same frames. Cycle-averaged (`ca`): both low-passed at 5 Hz
(`fwid.decomposition.lowpass`, the paper's split), RMS error in % of the truth's excursion
(max - min) -- the acceptance measure. Flapping harmonic n (`h1 h2 h3`): both
band-passed to `(n -+ 1/2) f` (differences of two 8th-order `lowpass`, `f` the mean flapping
frequency), RMS error in % of the truth's RMS in the band. Medians over the takes of a case.
`clock_ms`: the largest |estimated - true| clock offset [ms].

**Methods.** `fwid`: `fwid reconstruct RAW --out DIR [--body DelFly]` as a process (the CLI is
the contract; nothing of fwid's internals is used). `baseline`: `benchmarks/peers/finite_differences.py`
as a process (finite differences of positions and scipy Euler angles after a 40 Hz
Butterworth, the same load equations; it is handed the true clock offset).

**Speed** (`speed`): 16 Motive takes of 60 s at 200 Hz; wall seconds of the whole process,
`fwid reconstruct` cold (first run) and warm (a second run: JAX's compilation cache filled),
warm again with `--no-figures`, and the baseline, each run once; with each its CPU seconds
(user + system of the process) and the load average as it started.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's fwid
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # _provenance

LON = ("q", "u", "w", "theta", "X", "Z", "M")
DEFAULT = {"raw": "motive", "position_noise": 0.4, "rate": 200.0, "dropouts": 0.005, "clock_offset": None}


def grid(quick: bool) -> list[dict]:
    """The cases: the default, then one factor at a time."""
    cases = [("default", {})]
    noises = (0.1, 2.0) if quick else (0.1, 1.0, 2.0)
    rates = (100.0, 500.0) if quick else (100.0, 250.0, 500.0)
    drops = (0.0, 0.05) if quick else (0.0, 0.02, 0.05)
    offsets = (0.0013,) if quick else (-187.3021, 0.0013, 151.77)
    cases += [(f"pose noise {n:g} mm", {"position_noise": n}) for n in noises]
    cases += [(f"rate {r:g} Hz", {"rate": r}) for r in rates]
    cases += [(f"dropouts {100 * d:g} %", {"dropouts": d}) for d in drops]
    cases += [(f"clock offset {o:g} s", {"clock_offset": o}) for o in offsets]
    cases += [("fwid raw CSV (NED)", {"raw": "fwid"})]
    cases += [("take of 30 s", {"duration": 30.0}), ("take of 60 s", {"duration": 60.0}),
              ("take of 90 s", {"duration": 90.0}),
              ("fwid raw CSV (NED), 90 s", {"raw": "fwid", "duration": 90.0})]
    return [{"case": name, **DEFAULT, **over} for name, over in cases]


def simulate(folder: Path, case: dict, takes: int, duration: float, seed: int) -> None:
    duration = case.get("duration", duration)
    from fwid.synth import write_raw_flights

    noise = case["position_noise"]
    kw = {"position_noise": noise * 1e-3, "attitude_noise": 0.15 * noise / 0.4,
          "rate": case["rate"], "dropouts": case["dropouts"]}
    if case["clock_offset"] is not None:
        kw["clock_offset"] = case["clock_offset"]
    write_raw_flights(folder, raw=case["raw"], n_flights=takes, seed=seed, duration=duration, **kw)


def run(cmd: list[str], timeout: float = 1800.0) -> tuple[float, subprocess.CompletedProcess]:
    """Wall seconds and the process; `proc.cpu_s` its CPU seconds (user + system, all
    threads) and `proc.load` the 1-minute load average before it started."""
    import resource

    load = os.getloadavg()[0]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        proc = subprocess.CompletedProcess(cmd, 124, "", f"timed out after {timeout:.0f} s")
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc.cpu_s = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    proc.load = load
    return wall, proc


def fwid_reconstruct(raw: Path, out: Path, form: str, timeout: float = 1800.0,
                     figures: bool = True) -> tuple[float, subprocess.CompletedProcess]:
    cmd = [sys.executable, "-m", "fwid.cli", "reconstruct", str(raw), "--out", str(out)]
    cmd += ["--body", "DelFly"] if form == "motive" else []
    return run(cmd + ([] if figures else ["--no-figures"]), timeout)


def baseline(raw: Path, out: Path) -> tuple[float, subprocess.CompletedProcess]:
    offsets = {p.stem: json.loads(p.read_text())["truth"]["raw"]["clock_offset_s"]
               for p in (raw / "truth").glob("*.json") if p.stem != "vehicle"}
    off = raw.parent / f"{out.name}-offsets.json"
    off.write_text(json.dumps(offsets))
    return run([sys.executable, str(HERE / "peers" / "finite_differences.py"), str(raw), str(out),
                "--clock-offsets", str(off)])


def _read(path: Path) -> dict[str, np.ndarray]:
    d = np.genfromtxt(path, delimiter=",", names=True)
    return {c: np.asarray(d[c], float) for c in d.dtype.names}


def band_errors(rec: dict, truth: dict, edge: float = 0.5) -> dict:
    """Per channel of `LON`: `ca`, `h1`, `h2`, `h3` errors in % (module docstring)."""
    from fwid.decomposition import lowpass

    dt = truth["t"][1] - truth["t"][0]
    idx = np.rint((rec["t"] - truth["t"][0]) / dt).astype(int)
    ok = (idx >= 0) & (idx < truth["t"].size)
    idx, sel = idx[ok], np.flatnonzero(ok)
    if np.max(np.abs(truth["t"][idx] - rec["t"][sel])) > 1e-3 * dt:
        raise ValueError("the reconstructed flight is not on the take's time base")
    keep = slice(round(edge / dt), idx.size - round(edge / dt))
    f = float(np.mean(truth["f"][idx]))
    out = {}
    for c in LON:
        x, y = rec[c][sel], truth[c][idx]
        ca = lambda s: np.asarray(lowpass(s, dt, 5.0))[keep]  # noqa: E731
        e = ca(x) - ca(y)
        res = {"ca": float(100 * np.sqrt(np.mean(e**2)) / np.ptp(ca(y)))}
        for n in (1, 2, 3):
            hi = min((n + 0.5) * f, 0.49 / dt)
            band = lambda s: np.asarray(lowpass(s, dt, hi, order=8) - lowpass(s, dt, (n - 0.5) * f, order=8))[keep]  # noqa: E731
            bt = band(y)
            res[f"h{n}"] = float(100 * np.sqrt(np.mean((band(x) - bt) ** 2)) / np.sqrt(np.mean(bt**2)))
        out[c] = res
    return out


def score(rec_dir: Path, raw: Path) -> dict:
    """Median errors over the takes of a folder, and the clock offsets' errors."""
    per = []
    for tp in sorted((raw / "truth").glob("*.csv")):
        per.append(band_errors(_read(rec_dir / tp.name), _read(tp)))
    med = {c: {b: float(np.median([p[c][b] for p in per])) for b in per[0][c]} for c in LON}
    out = {"errors": med}
    rj = rec_dir / "reconstruction.json"
    if rj.exists():
        est = {Path(f["flight"]).stem: f.get("clock_offset_s") for f in json.loads(rj.read_text())["flights"]}
        errs = []
        for jp in (raw / "truth").glob("*.json"):
            if jp.stem in est and est[jp.stem] is not None:
                errs.append(abs(est[jp.stem] - json.loads(jp.read_text())["truth"]["raw"]["clock_offset_s"]))
        out["clock_ms"] = 1e3 * max(errs) if errs else None
    return out


def one_case(case: dict, takes: int, duration: float, seed: int, work: Path) -> dict:
    raw = work / "raw"
    t0 = time.perf_counter()
    simulate(raw, case, takes, duration, seed)
    res = dict(case, takes=takes, duration_s=case.get("duration", duration), simulate_s=time.perf_counter() - t0)
    for name, fn in (("fwid", lambda o: fwid_reconstruct(raw, o, case["raw"])),
                     ("baseline", lambda o: baseline(raw, o))):
        out = work / name
        wall, proc = fn(out)
        if proc.returncode != 0:
            res[name] = {"error": (proc.stderr.strip().splitlines() or ["?"])[-1], "rc": proc.returncode}
            continue
        try:
            res[name] = {"wall_s": wall, "cpu_s": proc.cpu_s, **score(out, raw)}
        except Exception as exc:  # a missing column or time base: report, go on
            res[name] = {"error": f"{type(exc).__name__}: {exc}"}
    return res


def speed(work: Path, takes: int, duration: float) -> dict:
    raw = work / "raw"
    t0 = time.perf_counter()
    simulate(raw, dict(DEFAULT), takes, duration, seed=1000)
    res = {"takes": takes, "duration_s": duration, "rate": 200.0, "simulate_s": time.perf_counter() - t0}
    cache = work / "jax-cache"  # an empty compilation cache: cold, then warm
    os.environ["FWID_JAX_CACHE"] = str(cache)
    for label in ("fwid_cold", "fwid_warm", "fwid_warm_no_figures"):
        wall, proc = fwid_reconstruct(raw, work / label, "motive", timeout=600.0,
                                      figures=label != "fwid_warm_no_figures")
        res[label] = {"wall_s": wall, "cpu_s": proc.cpu_s, "load": proc.load, "rc": proc.returncode}
        if proc.returncode != 0:
            res[label]["error"] = (proc.stderr.strip().splitlines() or ["?"])[-1]
    del os.environ["FWID_JAX_CACHE"]
    wall, proc = baseline(raw, work / "baseline")
    res["baseline"] = {"wall_s": wall, "cpu_s": proc.cpu_s, "load": proc.load, "rc": proc.returncode}
    for label in ("fwid_warm", "baseline"):
        if res[label]["rc"] == 0:
            try:
                res[label].update(score(work / label, raw))
            except Exception as exc:
                res[label]["error"] = f"{type(exc).__name__}: {exc}"
    return res


def _fmt(x, nd=1):
    return "-" if x is None else f"{x:.{nd}f}"


def markdown(res: dict) -> str:
    lines = ["# Reconstruction: raw takes to flight data, against the simulator's truth", "",
             f"Machine: {res['machine']}, load average {res['load_start']:.1f} at start, "
             f"{res.get('load_end', 0):.1f} at end.", "",
             "Errors in %: cycle-averaged (< 5 Hz) RMS error of the excursion; flapping harmonics "
             "h1-h3 RMS error of the band's RMS; medians over the takes. fwid: `fwid reconstruct` as a "
             "process; baseline: finite differences after a 40 Hz Butterworth (`peers/finite_differences.py`, "
             "given the true clock offset). See the script's docstring.", ""]
    head = ("| case | method | " + " | ".join(f"{c} ca" for c in LON) + " | M h1 | M h2 | M h3 | "
            "Z h1 | Z h2 | Z h3 | clock ms | wall s |")
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    for case in res["cases"]:
        for m in ("fwid", "baseline"):
            r = case.get(m, {})
            if "errors" not in r:
                lines.append(f"| {case['case']} | {m} | not run: {r.get('error', 'missing')} |")
                continue
            e = r["errors"]
            cells = [_fmt(e[c]["ca"]) for c in LON]
            cells += [_fmt(e[c][h]) for c in ("M", "Z") for h in ("h1", "h2", "h3")]
            cells += [_fmt(r.get("clock_ms"), 2), _fmt(r["wall_s"])]
            lines.append(f"| {case['case']} | {m} | " + " | ".join(cells) + " |")
    sp = res.get("speed")
    if sp:
        lines += ["", f"## Speed: {sp['takes']} takes of {sp['duration_s']:g} s at 200 Hz, whole process", "",
                  "Each run once, in a row, on a machine shared with other work: `cpu s` is the "
                  "process's CPU time (user + system, all threads), `load` the 1-minute load "
                  "average as it started (2 cores). `fwid_warm_no_figures`: `--no-figures`.", "",
                  "| run | wall s | cpu s | load | q ca % | Z ca % | M ca % | M h1 % |",
                  "|---|---:|---:|---:|---:|---:|---:|---:|"]
        for label in ("fwid_cold", "fwid_warm", "fwid_warm_no_figures", "baseline"):
            r = sp.get(label)
            if r is None:
                continue
            e = r.get("errors")
            cells = [_fmt(r["wall_s"]), _fmt(r.get("cpu_s")), _fmt(r.get("load"))]
            cells += ([_fmt(e[c]["ca"]) for c in ("q", "Z", "M")] + [_fmt(e["M"]["h1"])] if e else ["-"] * 4)
            lines.append(f"| {label} | " + " | ".join(cells) + (f" (failed: {r['error']})" if "error" in r else "") + " |")
        b = sp["baseline"]
        for label in ("fwid_warm", "fwid_warm_no_figures"):
            w = sp.get(label, {})
            if w.get("rc") == 0 and b.get("rc") == 0:
                lines += ["", f"`{label}` / baseline: wall {w['wall_s'] / b['wall_s']:.2f}, "
                          f"CPU {w['cpu_s'] / b['cpu_s']:.2f}."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a small grid, one short take per case")
    ap.add_argument("--no-speed", action="store_true", help="skip the 16 x 60 s speed row")
    ap.add_argument("--takes", type=int, default=None, help="takes per case (2; quick: 1)")
    ap.add_argument("--duration", type=float, default=None, help="seconds per take (10; quick: 6)")
    ap.add_argument("--speed-takes", type=int, default=None, help="takes of the speed row (16; quick: 4)")
    ap.add_argument("--speed-duration", type=float, default=None,
                    help="seconds per take of the speed row (60; quick: 20)")
    ap.add_argument("--only", default=None,
                    help="run only the cases whose name holds this text (no results file without --out)")
    ap.add_argument("--out", default=None, help="results JSON (default: benchmarks/results/reconstruction.json)")
    args = ap.parse_args(argv)
    if args.out is None and args.only is None:
        args.out = str(HERE / "results" / "reconstruction.json")
    takes = args.takes or (1 if args.quick else 2)
    duration = args.duration or (6.0 if args.quick else 10.0)
    import _provenance

    prov = _provenance.provenance(None if argv is None else [sys.argv[0], *argv])
    res = {"provenance": prov, "machine": f"{platform.machine()}, {os.cpu_count()} CPUs", "load_start": os.getloadavg()[0],
           "cases": []}
    for i, case in enumerate(grid(args.quick)):
        if args.only is not None and args.only not in case["case"]:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            r = one_case(case, takes, duration, 100 + i, Path(tmp))
        res["cases"].append(r)
        f, b = r.get("fwid", {}), r.get("baseline", {})
        show = lambda x: (f"q ca {x['errors']['q']['ca']:.2f} % M ca {x['errors']['M']['ca']:.2f} % "  # noqa: E731
                          f"M h1 {x['errors']['M']['h1']:.1f} %") if "errors" in x else x.get("error")
        print(f"{r['case']}: fwid {show(f)} | baseline {show(b)}", flush=True)
    if not args.no_speed:
        with tempfile.TemporaryDirectory() as tmp:
            res["speed"] = speed(Path(tmp), args.speed_takes or (4 if args.quick else 16),
                                 args.speed_duration or (20.0 if args.quick else 60.0))
        print(json.dumps({k: v for k, v in res["speed"].items() if not isinstance(v, dict)}), flush=True)
    res["load_end"] = os.getloadavg()[0]
    if args.out is None:
        print(markdown(res))
        return
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(_provenance.json_text(res, prov, indent=1))
    out.with_suffix(".md").write_text(_provenance.markdown(markdown(res), prov))
    print(_provenance.markdown(markdown(res), prov))
    print(f"wrote {out} and {out.with_suffix('.md')}")


if __name__ == "__main__":
    main()
