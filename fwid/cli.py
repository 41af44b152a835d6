"""The `fwid` command line (CONTRACTS section 2): thin, it calls the public API.

Exit codes: 0 on success, 2 on bad input (one line on stderr: what and where), 1 on an
internal error.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="fwid",
        description="Identify flapping-wing vehicle dynamics from flight data (Armanini et al.).",
    )
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("simulate", help="write simulated DelFly-like flights (the default data)")
    s.add_argument("out_dir")
    s.add_argument("--flights", type=int, default=4)
    s.add_argument("--axis", choices=("lon", "lat"), default="lon")
    s.add_argument("--effect", default="none")
    s.add_argument("--strength", type=float, default=1.0)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--duration", type=float, default=4.5, help="seconds per flight")
    s.add_argument("--drift", action="store_true", help="drifting flapping frequency")

    i = sub.add_parser("identify", help="identify a model from flights")
    i.add_argument("data", nargs="+", help="CSV files or folders of them")
    i.add_argument("--model", choices=("lon", "lat", "flap", "combined"), required=True)
    i.add_argument("--joint", action="store_true",
                   help="one parameter set for all flights (each keeps its own biases); with "
                   "--validate, each flight is also fitted alone and the report says which "
                   "validates better on the held-out flights (joint_vs_individual)")
    i.add_argument("--validate", nargs="+", default=[], metavar="DATA")
    i.add_argument("--out", default=None, help="folder for report.json and the figures")
    i.add_argument("--cutoff", type=float, default=5.0, help="cycle-averaged / flapping split [Hz]")
    i.add_argument("--quiet", action="store_true")

    d = sub.add_parser("diagnose", help="where the model misses, which effect explains it, "
                                        "how far the held-out error shrinks once it is added")
    d.add_argument("--train", nargs="+", required=True, metavar="DATA")
    d.add_argument("--test", nargs="+", required=True, metavar="DATA")
    d.add_argument("--axis", choices=("lon", "lat"), default="lon")
    d.add_argument("--out", default=None, help="folder for diagnosis.json and the figure")
    d.add_argument("--quiet", action="store_true")
    return p


def _simulate(args) -> int:
    from .synth import write_flights

    paths = write_flights(args.out_dir, n_flights=args.flights, axis=args.axis, seed=args.seed,
                          effect=args.effect, strength=args.strength, duration=args.duration,
                          drift=args.drift)
    print(f"fwid: wrote {len(paths)} {args.axis} flights to {args.out_dir}")
    return 0


def _identify(args) -> int:
    import fwid
    from .report import (identification_report, identification_summary, plot_flight_fit,
                         plot_poles, write_json)

    t0 = time.perf_counter()
    flights = fwid.load_flights(*args.data)
    validate = fwid.load_flights(*args.validate) if args.validate else []
    if args.model in ("flap", "combined"):
        from ._identify_flapping import identify_flapping  # issue 3

        return identify_flapping(args, flights, validate)
    ident = fwid.identify(flights, args.model, validate=validate, joint=args.joint,
                          cutoff=args.cutoff, progress=not args.quiet)
    report = identification_report(ident)
    print(identification_summary(report))
    if args.joint and validate and len(flights) > 1:  # issue 4: does sharing pay off?
        comparison = fwid.compare_joint(flights, args.model, validate=validate, joint=ident,
                                        cutoff=args.cutoff, progress=not args.quiet)
        report["joint_vs_individual"] = comparison.to_json()
        print("\n" + comparison.summary_text())
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        for ff in ident.estimation:
            plot_flight_fit(ff, path=out / f"fit_{Path(ff.name).stem}.png",
                            title=f"{ff.name}: estimation ({args.model})")
        for ff in ident.validation:
            plot_flight_fit(ff, path=out / f"validation_{Path(ff.name).stem}.png",
                            title=f"{ff.name}: validation ({args.model})")
        eigs = [fwid.eigenvalues(f.model, ident.consts) for f in ident.fits]
        labels = ident.flights if len(ident.fits) > 1 else ["joint" if args.joint else ident.flights[0]]
        plot_poles(eigs, labels, path=out / "poles.png", title=f"{args.model} model eigenvalues")
        write_json(out / "report.json", report)
        print(f"\nfwid: report and figures in {out}/ ({time.perf_counter() - t0:.1f} s)")
    return 0


def _diagnose(args) -> int:
    import fwid
    from .report import diagnosis_summary, plot_gap_map, write_json

    t0 = time.perf_counter()
    train = fwid.load_flights(*args.train)
    test = fwid.load_flights(*args.test)
    say = None if args.quiet else (lambda msg: print(f"fwid: {msg}", file=sys.stderr))
    diag = fwid.diagnose(train, test, axis=args.axis, progress=say)
    print(diagnosis_summary(diag))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        plot_gap_map(diag, path=out / "gap_map.png")
        write_json(out / "diagnosis.json", diag.to_json())
        print(f"\nfwid: diagnosis.json and gap_map.png in {out}/ "
              f"({time.perf_counter() - t0:.1f} s)")
    return 0


def main(argv=None) -> int:
    from ._errors import InputError

    args = _parser().parse_args(argv)
    try:
        if args.command == "simulate":
            return _simulate(args)
        if args.command == "identify":
            return _identify(args)
        if args.command == "diagnose":
            return _diagnose(args)
    except InputError as e:
        print(f"fwid: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fwid: interrupted", file=sys.stderr)
        return 1
    except Exception as e:  # internal error: short message plus where, for a bug report
        import traceback

        tb = traceback.extract_tb(e.__traceback__)[-1]
        print(f"fwid: internal error: {type(e).__name__}: {e} (at {tb.filename}:{tb.lineno}); "
              "please report it", file=sys.stderr)
        return 1
    return 1


if __name__ == "__main__":
    sys.exit(main())
