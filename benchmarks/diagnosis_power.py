"""Power of `fwid.diagnose` on a randomised benchmark that cannot be passed by tuning.

Cases (built deterministically by `cases(half)`):

- every catalogue effect x form x strength {0.25, 0.5, 1, 2} x flights {4+4, 6+6, 8+8};
- clean flights (`none`, 4 per flight count) and the out-of-catalogue effects (`turbulence`,
  `cg-offset`, `battery-sag`; `unsteady-aero` and `sensor-offset` were here before they
  joined the catalogue as `unsteady-aero` and `time-offset`) at strengths {1, 2} x flight
  counts: the
  right verdict names no catalogue entry;
- every pair of catalogue effects at strength 1 with 6+6 flights, forms drawn from the half:
  both should be in the result's `effects`.

Each case draws, from its own generator: a randomised vehicle (`fwid.synth.random_vehicle`,
every derivative and Fourier coefficient within +-30 %, stable; the same for all its training
and test flights), a noise scale U(0.5, 2), a flight length U(2.5, 8) s, a sample rate from
{100, 200, 300, 500} Hz, the input (the 3211/doublet/211/pulse cycle of `write_flights`, or
one of them for every flight) and the axis (among those whose manoeuvre shows the form).

**Split**: forms of even index (0, 2) with even seeds are the `dev` half, forms of odd index
(1, 3) with odd seeds the `heldout` half, and the forms in `HELDOUT_ONLY` (at least one per
family: the direction-dependent, lag-plus-delay, saturating and backlash actuators, saturating
and one-sided aerodynamic nonlinearities, a Wagner-like lag, one modulated flapping harmonic, a
gyroscopic coupling, a resynchronised clock and a saturating thrust-frequency law) are in the
`heldout` half only; clean and out-of-catalogue cases
split by seed parity. Choose thresholds on `dev`, report `heldout` only.

Per case: write the flights blind (sidecars deleted, `diagnosis._write`), `fwid.diagnose`,
then the SINDy peer (`peers/sindy.py`, unless `--no-peer`) on the same flights, timed each;
one JSON line in `results/diagnosis_power_{half}.jsonl` (the peer's verdict, kept families
and wall time under `sindy`); then the summary `diagnosis_power_{half}.md` (with the peer's
row beside fwid's) and the power curves `diagnosis_power_{half}.png` (`_power_summary.py`).

    python benchmarks/diagnosis_power.py --half dev [--seeds 2] [--workers 1] [--limit N]
        [--subset kind=single effect=flap-coupling ... ['|' kind=pair ...]] [--out ...] [--no-peer]
    python benchmarks/diagnosis_power.py --summarise benchmarks/results/diagnosis_power_dev.jsonl

**The detection limit's promise** (`--promise`): every single case records its truth's own
held-out gain (`truth_gain_pct`: the first-round cross-fitted gain of the true effect's
catalogue family, the family sized inside the fitting flights, so the model with the true
effect as the catalogue can fit it) and fwid's `detection` block. A case whose truth gains less
than `WEAK_PCT` is weak; fwid says how many flights of the same kind find its gain with 80 %
power (`flights_for_truth`, `fwid.diagnosis._detection.flights_needed`). `--promise` reruns
every weak case at that count (training and test halves as the case splits them, at most
`--promise-max` a side) and counts how often the effect is then named; the promise holds when
that is at least 80 %. Lines in `results/diagnosis_power_{half}_promise.jsonl`, the table in
the summary.
"""

from __future__ import annotations

import argparse
import functools
import itertools
import json
import multiprocessing as mp
import sys
import tempfile
import time
import zlib
from pathlib import Path

import numpy as np
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's fwid first
sys.path.insert(0, str(Path(__file__).resolve().parent))

STRENGTHS = (0.25, 0.5, 1.0, 2.0)
COUNTS = (4, 6, 8)
OOC_STRENGTHS = (1.0, 2.0)
CLEAN_PER_COUNT = 4
PAIR_COUNT = 6
RATES = (100.0, 200.0, 300.0, 500.0)
INPUTS = ("cycle", "3211", "211", "doublet", "pulse")
#: Held-out gain [%] of the truth below which a case is weak (the promise is checked on it).
WEAK_PCT = 4.0
HALVES = ("dev", "heldout")
#: Forms in the held-out half only, whatever their index: members of a family that the
#: development half never shows (the family, not a form, must generalise).
HELDOUT_ONLY = {"actuator-dynamics": ("asymmetric", "lag-delay", "saturation", "backlash"),
                "nonlinear-aero": ("saturation", "one-sided"),
                "unsteady-aero": ("wagner",),
                "flap-coupling": ("harmonic",),
                "lon-lat-coupling": ("gyroscopic",),
                "time-offset": ("resync",),
                "flap-frequency": ("saturating",)}


def _rng(case_key: str, seed: int):
    return np.random.default_rng([seed, zlib.crc32(case_key.encode())])


def _draw(case: dict, rng) -> dict:
    """The case's random conditions (vehicle seed, noise, length, rate, input)."""
    case["vehicle_seed"] = int(rng.integers(2**31 - 1))
    case["noise"] = float(rng.uniform(0.5, 2.0))
    case["duration"] = float(rng.uniform(2.5, 8.0))
    case["rate"] = float(rng.choice(RATES))
    case["input"] = str(rng.choice(INPUTS))
    return case


def cases(half: str = "dev", seeds: int = 2) -> list[dict]:
    """The cases of `half`, in a fixed shuffled order (so `--limit` takes a mixed slice)."""
    from fwid.synth import EFFECTS, FORMS, OUT_OF_CATALOGUE, form_axes

    parity = HALVES.index(half)
    catalogue = EFFECTS[1:]
    forms = {e: [f for i, f in enumerate(FORMS[e])
                 if (i % 2 == parity and f not in HELDOUT_ONLY.get(e, ()))
                 or (half == "heldout" and f in HELDOUT_ONLY.get(e, ()))] for e in catalogue}
    out = []

    def add(kind, effect, form, strength, n, seed, rep=0):
        key = f"{kind}|{effect}|{form}|{strength}|{n}|{seed}|{rep}"
        rng = _rng(key, seed)
        names, fnames = effect.split("+"), form.split("+")
        axes = [a for a in ("lon", "lat")
                if all(a in form_axes(e, f) for e, f in zip(names, fnames))]
        case = {"kind": kind, "effect": effect, "form": form, "strength": strength,
                "n": n, "seed": seed, "rep": rep, "axis": str(rng.choice(axes))}
        out.append(_draw(case, rng))

    for seed in range(parity, 2 * seeds, 2):
        for e in catalogue:
            for f, s, n in itertools.product(forms[e], STRENGTHS, COUNTS):
                add("single", e, f, s, n, seed)
        for n, rep in itertools.product(COUNTS, range(CLEAN_PER_COUNT)):
            add("clean", "none", "none", 0.0, n, seed, rep)
        for e, s, n in itertools.product(OUT_OF_CATALOGUE, OOC_STRENGTHS, COUNTS):
            add("out", e, FORMS[e][0], s, n, seed)
        for a, b in itertools.combinations(catalogue, 2):
            rng = _rng(f"pair|{a}|{b}|{seed}", seed)
            pairs = [(fa, fb) for fa in forms[a] for fb in forms[b]
                     if set(form_axes(a, fa)) & set(form_axes(b, fb))]
            fa, fb = pairs[int(rng.integers(len(pairs)))]
            add("pair", f"{a}+{b}", f"{fa}+{fb}", 1.0, PAIR_COUNT, seed)
    order = np.random.default_rng(12 + parity).permutation(len(out))
    return [out[i] for i in order]


def select(all_cases: list[dict], subset: list[str], limit: int | None) -> list[dict]:
    """`subset`: `key=value[,value]` filters on case fields (all must hold), in groups
    separated by `|` (a case in any group is taken, in the cases' order); then the first
    `limit` cases."""
    groups, group = [], []
    for cond in subset:
        if cond == "|":
            groups.append(group)
            group = []
        else:
            group.append(cond)
    groups.append(group)

    def holds(c, cond):
        key, _, vals = cond.partition("=")
        allowed = set(vals.split(","))
        return str(c.get(key)) in allowed or (key == "effect"
                                              and bool(allowed & set(c["effect"].split("+"))))
    out = [c for c in all_cases if any(all(holds(c, x) for x in g) for g in groups)]
    return out[:limit] if limit else out


def _record_candidates(diag) -> list[dict]:
    out = []
    for c in getattr(diag, "candidates", []) or []:
        rec = {k: c.get(k) for k in ("effect", "significant", "p", "confidence", "shrink_pct")
               if k in c}
        out.append(rec)
    return out


def case_flights(case: dict, rec: dict):
    """The case's training and test flights, written blind and loaded back (`rec` gains the
    effect's noise ratio); `None` when the simulation diverged (recorded in `rec`)."""
    import fwid
    from diagnosis import _write
    from fwid.synth import effect_noise_ratio, random_vehicle

    vehicle = random_vehicle(case["vehicle_seed"])
    kw = {"form": case["form"], "vehicle": vehicle, "noise": case["noise"],
          "duration": case["duration"], "rate": case["rate"]}
    if case["input"] != "cycle":
        kw["input"] = case["input"]
    effect = case["effect"]
    if effect != "none":
        r = effect_noise_ratio(effect, case["form"], case["strength"], (case["axis"],),
                               vehicle=vehicle)
        rec["noise_ratio"] = r["max"]
    with tempfile.TemporaryDirectory() as d:
        base = zlib.crc32(json.dumps(case, sort_keys=True).encode())  # flight seeds
        _write(f"{d}/train", case["n"], case["axis"], base, effect, case["strength"], **kw)
        _write(f"{d}/test", case["n"], case["axis"], base + 500, effect, case["strength"], **kw)
        train, test = fwid.load_flights(f"{d}/train"), fwid.load_flights(f"{d}/test")
    cols = ("q", "u", "w", "p", "r", "v", "X", "Z", "M", "Y", "L", "N")
    if not all(np.all(np.isfinite(np.asarray(f[c]))) for f in train + test for c in cols):
        rec["error"] = "diverged"  # e.g. the quadratic nonlinear-aero at strength 2
        return None
    return train, test


def run_peer(train, test, axis: str) -> dict:
    """The SINDy peer (`peers/sindy.py`) on the case's flights: its `verdict`, `kept` families
    (best first), each family's test gain and kept terms, and `wall_s`; `error` instead when
    it failed (fwid's record stands either way)."""
    t0 = time.perf_counter()
    try:
        from peers.sindy import diagnose

        got = diagnose(train, test, axis)
    except Exception as exc:  # noqa: BLE001 - a benchmark records, it does not stop
        return {"error": f"{type(exc).__name__}: {exc}", "wall_s": time.perf_counter() - t0}
    return {"verdict": got["verdict"], "kept": got["kept"], "families": got["families"],
            "wall_s": got["wall_s"]}


def run_case(case: dict, peer: bool = True) -> dict:
    """Simulate, diagnose and score one case (errors are recorded, not raised); with `peer`
    the SINDy peer runs on the same flights after fwid (`rec["sindy"]`)."""
    import fwid

    rec = dict(case)
    try:
        flights = case_flights(case, rec)
        if flights is None:
            return rec
        train, test = flights
        t0 = time.perf_counter()
        diag = fwid.diagnose(train, test, axis=case["axis"], simulation=False,
                             process_noise=False)
        rec["wall_s"] = time.perf_counter() - t0
    except Exception as exc:  # noqa: BLE001 - a benchmark records, it does not stop
        rec["error"] = f"{type(exc).__name__}: {exc}"
        return rec
    if peer:
        rec["sindy"] = run_peer(train, test, case["axis"])
    rec["verdict"] = diag.verdict
    effects = getattr(diag, "effects", None)
    if effects is not None:
        rec["effects"] = [e if isinstance(e, str) else e.get("effect") for e in effects]
        rec["effects_detail"] = [e for e in effects if isinstance(e, dict)]
    rec["candidates"] = _record_candidates(diag)
    v = diag.lead if hasattr(diag, "lead") else (
        diag.candidate(diag.verdict) if diag.verdict != "none" else None)
    rec["shrink_pct"] = v.get("shrink_pct") if v else None
    u = getattr(diag, "unexplained", None)
    if u:
        rec["unexplained"] = {k: u.get(k) for k in ("probe", "drivers", "test_shrink_pct", "p",
                                                    "redness_after")}
    for k in ("disturbance", "first_round", "rounds", "confidence_set", "detection"):
        if getattr(diag, k, None) is not None:
            rec[k] = getattr(diag, k)
    truth_gain(rec)
    return rec


def truth_gain(rec: dict) -> None:
    """`rec` (a single or pair case's) gains `truth_gain_pct`: its true effect's first-round
    cross-fitted gain (a pair: the smaller of its two effects' own gains, each in
    `truth_gains_pct`); a single case below `WEAK_PCT` also `flights_for_truth` (fwid's
    flights for that gain, training and test together; `None`: no number finds it)."""
    from fwid.diagnosis._detection import flights_needed

    rounds = rec.get("first_round") or {}
    if rec["kind"] == "pair":
        gains = {e: rounds[e]["gain_pct"] for e in rec["effect"].split("+") if e in rounds}
        if len(gains) == 2:
            rec["truth_gains_pct"] = gains
            rec["truth_gain_pct"] = min(gains.values())
        return
    first = rounds.get(rec["effect"])
    if rec["kind"] != "single" or first is None:
        return
    rec["truth_gain_pct"] = first["gain_pct"]
    if first["gain_pct"] < WEAK_PCT and rec.get("detection"):
        rec["flights_for_truth"] = flights_needed(rec["detection"], max(first["gain_pct"], 0.0))


def promise_case(rec: dict, most: int) -> dict:
    """Rerun the weak case `rec` at fwid's flight count for its truth's gain (half for
    training, half for test, at most `most` a side): was the effect named?"""
    import math

    m = rec["flights_for_truth"]
    n = math.ceil(m / 2)
    out = {k: rec[k] for k in ("kind", "effect", "form", "strength", "n", "seed", "axis",
                               "truth_gain_pct")}
    out.update(flights_for_truth=m, n_promise=n)
    if n > most:
        out["skipped"] = f"needs {n} flights a side (> {most})"
        return out
    case = {k: v for k, v in rec.items() if k in ("kind", "effect", "form", "strength", "seed",
                                                    "rep", "axis", "vehicle_seed", "noise",
                                                    "duration", "rate", "input")}
    again = run_case({**case, "n": n}, peer=False)
    out.update(verdict=again.get("verdict"), error=again.get("error"),
               found=rec["effect"] in (again.get("effects") or []) or
               again.get("verdict") == rec["effect"], wall_s=again.get("wall_s"),
               rerun_first_round=(again.get("first_round") or {}).get(rec["effect"]),
               rerun_limit_pct=(again.get("detection") or {}).get("limit_pct"))
    return out


def main(argv=None):
    from _power_summary import summarise

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--half", choices=HALVES, default="dev")
    ap.add_argument("--seeds", type=int, default=2, help="seeds per half")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--limit", type=int, default=None, help="run only the first N cases")
    ap.add_argument("--subset", nargs="*", default=[], help="filters key=value[,value]")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--list", action="store_true", help="print the cases and stop")
    ap.add_argument("--no-peer", action="store_true",
                    help="skip the SINDy peer (by default it runs on every case's flights)")
    ap.add_argument("--summarise", metavar="FILE.jsonl", help="only rewrite the summary")
    ap.add_argument("--promise", action="store_true",
                    help=f"rerun each weak case (truth gain < {WEAK_PCT:g} %%) at the flights "
                         "fwid says find its gain; with --summarise, from that file's cases")
    ap.add_argument("--promise-max", type=int, default=16,
                    help="most flights a side a promise rerun may take")
    args = ap.parse_args(argv)

    if args.summarise:
        path = Path(args.summarise)
        results = _provenance.records(path)
        for r in results:
            if "error" not in r:  # the rule of this checkout, not of the run
                truth_gain(r)
        promised = (run_promise(results, path.with_suffix(""), args) if args.promise else
                    _promised(path.with_suffix("")))
        summarise(results, path.with_suffix(""), note=f"recomputed from {path.name}",
                  promised=promised)
        return
    todo = select(cases(args.half, args.seeds), args.subset, args.limit)
    if args.list:
        for c in todo:
            print(json.dumps(c))
        print(f"{len(todo)} cases", file=sys.stderr)
        return
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"diagnosis_power_{args.half}"
    t0 = time.perf_counter()

    def line(r):
        p = r.get("sindy")
        peer = f"; sindy {p.get('verdict', p.get('error'))} ({p['wall_s']:.1f} s)" if p else ""
        return (f"{r['kind']} {r['effect']}/{r['form']} s={r['strength']:g} "
                f"{r['n']}+{r['n']} {r['axis']}: {r.get('verdict', r.get('error'))} "
                f"effects={r.get('effects')} ({r.get('wall_s', 0):.1f} s){peer}")

    results = run_pool(stem.with_suffix(".jsonl"), functools.partial(run_case,
                                                                     peer=not args.no_peer),
                       todo, args.workers, line)
    promised = run_promise(results, stem, args) if args.promise else None
    cmd = "python benchmarks/diagnosis_power.py " + " ".join(sys.argv[1:] if argv is None else argv)
    summarise(results, stem, note=f"`{cmd}`, {args.workers} worker(s), "
              f"{time.perf_counter() - t0:.0f} s", promised=promised)


def run_promise(results: list[dict], stem: Path, args) -> list[dict]:
    """`--promise`: every weak case with a finite flight count rerun at it
    (`promise_case`), one line each in `{stem}_promise.jsonl`."""
    weak = [r for r in results if r.get("flights_for_truth")]
    return run_pool(Path(f"{stem}_promise.jsonl"),
                    functools.partial(promise_case, most=args.promise_max), weak, args.workers,
                    lambda r: (f"promise: {r['effect']}/{r['form']} truth gain "
                               f"{r['truth_gain_pct']:.2f} %: {r['flights_for_truth']} flights "
                               f"-> {r.get('skipped') or r.get('verdict', r.get('error'))}"))


def run_pool(path: Path, work, todo: list, workers: int, line) -> list[dict]:
    """`work` on every item of `todo` in `workers` processes, each result one JSON line in
    `path` (after the provenance line) as it comes and one progress line (`line(result)`)."""
    out = []
    with open(path, "w") as fh, mp.get_context("spawn").Pool(workers) as pool:
        fh.write(_provenance.jsonl_first_line())
        for i, r in enumerate(pool.imap_unordered(work, todo), 1):
            out.append(r)
            fh.write(json.dumps(r) + "\n")
            fh.flush()
            print(f"[{i}/{len(todo)}] {line(r)}", flush=True)
    return out


def _promised(stem: Path) -> list[dict] | None:
    """The promise reruns recorded beside `stem`, if any."""
    path = Path(f"{stem}_promise.jsonl")
    return _provenance.records(path) if path.is_file() else None


if __name__ == "__main__":
    main()
