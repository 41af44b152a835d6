"""`fwid diagnose`: where the model misses, which effect explains it, how far the held-out
error shrinks once it is added."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from ._inputs import DIAGNOSE_COLUMNS, check_paths, read_sets, window_of


def diagnose(args) -> int:
    t0 = time.perf_counter()
    window = window_of(args)
    check_paths(args.train, args.test)
    train, test = read_sets(args.train, args.test, require=DIAGNOSE_COLUMNS[args.axis],
                            window=window)
    import fwid  # JAX from here on: every file has been read and checked
    from fwid.report import diagnosis_summary, write_diagnosis

    train_records, test_records = train, test
    train, test = fwid.data.build_flights(train), fwid.data.build_flights(test)
    say = None if args.quiet else (lambda msg: print(f"fwid: {msg}", file=sys.stderr))
    from fwid.diagnosis import read_reconstruction

    diag = fwid.diagnose(train, test, axis=args.axis, simulation=not args.no_simulation,
                         process_noise=not args.no_process_noise,
                         reconstruction=read_reconstruction(
                             [r.path for r in train_records + test_records]),
                         progress=say)
    # where the flights are (diagnosis.json's `train` and `test` name them only): for
    # `fwid design --discriminate`, which fits the two closest effects' models again
    diag.settings = {**diag.settings,
                     "train_paths": [str(Path(r.path).resolve()) for r in train_records],
                     "test_paths": [str(Path(r.path).resolve()) for r in test_records],
                     **({} if window is None else {"window": list(window)})}
    if args.out and not args.no_next_flight and diag.next_flight is not None:
        from ._discriminate import next_flight_input

        if say:
            say("designing the next flight that tells the two leading explanations apart")
        diag.next_input = next_flight_input(diag.to_json(), train, Path(args.out), say)
    print(diagnosis_summary(diag))
    if args.out:
        out = Path(args.out)
        written = write_diagnosis(diag, out)
        print(f"\nfwid: {', '.join(written)} in {out}/ ({time.perf_counter() - t0:.1f} s)")
    else:
        print("\nfwid: nothing written (give --out DIR for diagnosis.json and the gap map)")
    return 0
