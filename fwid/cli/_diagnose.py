"""`fwid diagnose`: where the model misses, which effect explains it, how far the held-out
error shrinks once it is added."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from ._inputs import DIAGNOSE_COLUMNS, check_paths, read_sets


def diagnose(args) -> int:
    t0 = time.perf_counter()
    check_paths(args.train, args.test)
    train, test = read_sets(args.train, args.test, require=DIAGNOSE_COLUMNS[args.axis])
    import fwid  # JAX from here on: every file has been read and checked
    from fwid.report import (
        diagnosis_summary,
        identification_report,
        parameters_csv,
        plot_gap_map,
        plot_gap_sim,
        write_json,
        write_text,
    )

    train, test = fwid.data.build_flights(train), fwid.data.build_flights(test)
    say = None if args.quiet else (lambda msg: print(f"fwid: {msg}", file=sys.stderr))
    diag = fwid.diagnose(train, test, axis=args.axis, simulation=not args.no_simulation,
                         progress=say)
    print(diagnosis_summary(diag))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        plot_gap_map(diag, path=out / "gap_map.png")
        written = ["diagnosis.json", "gap_map.png"]
        if diag.models is not None:
            plot_gap_sim(diag, path=out / "gap_sim.png")
            written.append("gap_sim.png")
            if diag.models.augmented is not None:  # the model to carry on with
                rep = identification_report(diag.models.augmented)
                write_json(out / "augmented_model.json", rep)
                write_text(out / "augmented_parameters.csv", parameters_csv(rep["parameters"]))
                written += ["augmented_model.json", "augmented_parameters.csv"]
        write_json(out / "diagnosis.json", diag.to_json())
        print(f"\nfwid: {', '.join(written)} in {out}/ ({time.perf_counter() - t0:.1f} s)")
    else:
        print("\nfwid: nothing written (give --out DIR for diagnosis.json and the gap map)")
    return 0
