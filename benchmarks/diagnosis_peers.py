"""fwid's diagnosis beside a peer (the SINDy baseline, `peers/sindy.py`) on the same cases.

The cases and their flights are `diagnosis_power.py`'s (its `cases`, `select` and
`case_flights`): the same randomised vehicles, noise, inputs and development / held-out split.
Each case's flights are written once; `fwid.diagnose` (as in `diagnosis_power.py`: no
simulation block, no process-noise fit) and the peer run on them in the same process, one
after the other, timed each.

Scores per row (held-out half only is reported by convention):

- *right*: single effects, the verdict is the injected effect; clean and out-of-catalogue
  cases, the verdict names no catalogue entry;
- *decisive*: right, and nothing else kept: for fwid, the confidence set holds the truth alone
  (clean/out: no explanation naming an entry); for SINDy, the only family whose kept terms lower
  the test error is the truth (clean/out: no such family);
- *false alarms*: a catalogue name as the verdict of a clean or out-of-catalogue case.

    python benchmarks/diagnosis_peers.py --half heldout --subset strength=1.0,0.0 n=6 \\
        --limit 14 [--peer sindy] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's fwid first
sys.path.insert(0, str(Path(__file__).resolve().parent))

import _provenance  # noqa: E402
from diagnosis_power import HALVES, case_flights, cases, select  # noqa: E402

PEERS = ("sindy",)


def _fwid(train, test, axis) -> dict:
    import fwid

    t0 = time.perf_counter()
    diag = fwid.diagnose(train, test, axis=axis, simulation=False, process_noise=False)
    wall = time.perf_counter() - t0
    return {"verdict": diag.verdict, "confidence_set": diag.confidence_set, "wall_s": wall}


def _sindy(train, test, axis, derivatives=True) -> dict:
    from peers.sindy import diagnose

    return diagnose(train, test, axis, derivatives=derivatives)


def _key(case: dict) -> str:
    return json.dumps({k: case[k] for k in ("kind", "effect", "form", "strength", "n", "seed",
                                            "rep")}, sort_keys=True)


def run_case(case: dict, fwid_rec: dict | None = None, derivatives: bool = True) -> dict:
    """Both methods on one case; with `fwid_rec` (fwid's record of the same case from an
    earlier run) only the peer runs."""
    rec = dict(case)
    try:
        flights = case_flights(case, rec)
        if flights is None:
            return rec
        train, test = flights
        if fwid_rec is not None:
            rec["fwid"] = fwid_rec
        else:
            f = _fwid(train, test, case["axis"])
            rec["fwid"] = {"verdict": f["verdict"], "wall_s": f["wall_s"],
                           "confidence_set": f["confidence_set"]}
        rec["sindy"] = _sindy(train, test, case["axis"], derivatives)
    except Exception as exc:  # noqa: BLE001 - a benchmark records, it does not stop
        rec["error"] = f"{type(exc).__name__}: {exc}"
    return rec


def score(rec: dict, who: str) -> dict | None:
    """right / decisive / false alarm of `who` (`fwid` or `sindy`) on one case."""
    from fwid.diagnosis import EFFECT_NAMES

    r = rec.get(who)
    if r is None:
        return None
    quiet = rec["kind"] in ("clean", "out")
    named = r["verdict"] in EFFECT_NAMES
    right = (not named) if quiet else r["verdict"] == rec["effect"]
    if who == "fwid":
        sets = [frozenset(e for e in x["explanation"] if e in EFFECT_NAMES)
                for x in r.get("confidence_set") or []]
        truth = frozenset() if quiet else frozenset([rec["effect"]])
        alone = bool(sets) and all(s == truth for s in sets)
    else:
        alone = r["kept"] == ([] if quiet else [rec["effect"]])
    return {"right": right, "decisive": right and alone, "alarm": quiet and named}


def table(results: list[dict]) -> list[str]:
    out = ["| method | cases | right | decisive | false alarms (clean + out) | "
           "wall s per case (median, max) |", "|---|---|---|---|---|---|"]
    for who in ("fwid",) + PEERS:
        sc = [(r, score(r, who)) for r in results]
        sc = [(r, s) for r, s in sc if s is not None]
        n = len(sc)
        quiet = sum(r["kind"] in ("clean", "out") for r, _ in sc)
        walls = [r[who]["wall_s"] for r, _ in sc]
        out.append(f"| {who} | {n} | {sum(s['right'] for _, s in sc)}/{n} | "
                   f"{sum(s['decisive'] for _, s in sc)}/{n} | "
                   f"{sum(s['alarm'] for _, s in sc)}/{quiet} | "
                   f"{np.median(walls):.1f}, {max(walls):.1f} |" if n else f"| {who} | 0 |")
    return out


def per_case(results: list[dict]) -> list[str]:
    out = ["| kind | effect / form | axis | fwid verdict (set size) | SINDy verdict (families "
           "kept: test gain %) | fwid s | SINDy s |", "|---|---|---|---|---|---|---|"]
    for r in results:
        if "fwid" not in r or "sindy" not in r:
            out.append(f"| {r['kind']} | {r['effect']} / {r['form']} | {r['axis']} | "
                       f"{r.get('error')} | | | |")
            continue
        fams = ", ".join(f"{k}: {v['gain_pct']:.1f}" for k, v in
                         sorted(r["sindy"]["families"].items(), key=lambda kv: -kv[1]["gain_pct"]))
        out.append(f"| {r['kind']} | {r['effect']} / {r['form']} | {r['axis']} | "
                   f"{r['fwid']['verdict']} ({len(r['fwid']['confidence_set'] or [])}) | "
                   f"{r['sindy']['verdict']} ({fams or '-'}) | {r['fwid']['wall_s']:.1f} | "
                   f"{r['sindy']['wall_s']:.1f} |")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--half", choices=HALVES, default="heldout")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--limit", type=int, default=None)
    ap.add_argument("--subset", nargs="*", default=[])
    ap.add_argument("--peer", choices=PEERS, default="sindy")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--summarise", metavar="FILE.jsonl",
                    help="only rewrite the summary of a finished run (its provenance kept)")
    ap.add_argument("--note", default="", help="with --summarise: a line about the run")
    ap.add_argument("--reuse-fwid", metavar="FILE.jsonl",
                    help="take fwid's records of the same cases from an earlier run; run only "
                    "the peer")
    ap.add_argument("--no-derivatives", action="store_true",
                    help="the SINDy library without the states' time derivatives")
    ap.add_argument("--name", default="", help="suffix of the results files")
    args = ap.parse_args(argv)
    if args.summarise:
        path = Path(args.summarise)
        first = json.loads(path.read_text().split("\n", 1)[0])["provenance"]
        results = _provenance.records(path)
        note = (f"Recomputed from `{path.name}`, whose run is the command and commit above; "
                f"{len(results)} cases, one process, one case at a time. {args.note}")
        path.with_suffix(".md").write_text(_provenance.markdown(_text(args.half, results, note),
                                                                first))
        return
    todo = select(cases(args.half, args.seeds), args.subset, args.limit)
    if args.reuse_fwid:  # exactly the earlier run's cases (the generator may have grown since)
        fields = ("kind", "effect", "form", "strength", "n", "seed", "rep", "axis",
                  "vehicle_seed", "noise", "duration", "rate", "input")
        todo = [{k: r[k] for k in fields} for r in _provenance.records(Path(args.reuse_fwid))]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"diagnosis_peers_{args.half}{args.name}"
    earlier = ({_key(r): r["fwid"] for r in _provenance.records(Path(args.reuse_fwid))
                if "fwid" in r} if args.reuse_fwid else {})
    results = []
    t0 = time.perf_counter()
    prov = _provenance.provenance()
    with open(stem.with_suffix(".jsonl"), "w") as fh:
        fh.write(_provenance.jsonl_first_line(prov))
        for i, case in enumerate(todo, 1):
            r = run_case(case, earlier.get(_key(case)) if args.reuse_fwid else None,
                         not args.no_derivatives)
            results.append(r)
            fh.write(json.dumps(r) + "\n")
            fh.flush()
            print(f"[{i}/{len(todo)}] {r['kind']} {r['effect']}/{r['form']} {r['axis']}: "
                  f"fwid {r.get('fwid', {}).get('verdict', r.get('error'))}, "
                  f"sindy {r.get('sindy', {}).get('verdict')}", flush=True)
    load = os.getloadavg()
    note = (f"{len(todo)} cases, {time.perf_counter() - t0:.0f} s in all, load average "
            f"{load[0]:.1f} / {load[1]:.1f} (1 / 5 min) at the end; one process, one case at a "
            "time.")
    text = _text(args.half, results, note)
    stem.with_suffix(".md").write_text(_provenance.markdown(text, prov))
    print(text)


def _text(half, results, note) -> str:
    return "\n".join([
        f"# fwid diagnose beside a SINDy peer ({half} half)", "",
        f"`diagnosis_power.py`'s generator, the same flights for both. {note}", "",
        "Right: the injected effect (single), no catalogue name (clean, out of catalogue). "
        "Decisive: right and nothing else kept (fwid: the confidence set; SINDy: the families "
        "whose kept terms lower the test error by more than its `MIN_GAIN_PCT`). fwid runs "
        "without its simulation block and process-noise fit, as in `diagnosis_power.py`.", "",
        *table(results), "", "## Per case", "", *per_case(results), ""])


if __name__ == "__main__":
    main()
