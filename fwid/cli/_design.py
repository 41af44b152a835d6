"""`fwid design`: the test input for the next flight, designed through the identified model
(the test-input format)."""

from __future__ import annotations

import sys
import time
from pathlib import Path


def design(args) -> int:
    t0 = time.perf_counter()
    from fwid._errors import InputError

    if args.discriminate is not None:
        from ._discriminate import discriminate

        return discriminate(args)
    if args.model is None or args.source is None:
        raise InputError("design: give --model lon|lat and --from REPORT.json (the report of "
                         "`fwid identify --out DIR`)")
    if args.amplitude is None:
        raise InputError("design: give --amplitude (the peak deflection [rad], perturbation "
                         "from trim)")
    from fwid.design._design import check_limits

    check_limits(args.duration, args.amplitude, args.quiet, args.rate, args.switch_rate)
    if not Path(args.source).is_file():
        raise InputError(f"{args.source}: no such report; give the report.json that `fwid "
                         "identify --out DIR` wrote")
    import fwid
    from fwid.report._design import write_design

    d = fwid.design_input(args.source, model=args.model, duration=args.duration,
                          amplitude=args.amplitude, quiet=args.quiet,
                          parametrisation=args.parametrisation, switch_rate=args.switch_rate,
                          rate=args.rate, restarts=args.restarts, seed=args.seed,
                          criterion=args.criterion,
                          attitude_limit="3211" if args.attitude_limit is None
                          else args.attitude_limit,
                          progress=(lambda m: print(f"fwid: {m}", file=sys.stderr))
                          if not args.quiet_progress else False)
    written = write_design(d, Path(args.out))
    gm = d.to_json()["geometric_mean_ratio"]
    print(f"fwid: designed {d.control} ({d.settings['parametrisation']}), predicted std "
          f"{gm:.2f}x smaller than a 3211 of the same amplitude and length (geometric mean "
          f"over {len(d.vehicle_names)} parameters)")
    print(f"fwid: {', '.join(written)} in {args.out}/ ({time.perf_counter() - t0:.1f} s)")
    return 0
