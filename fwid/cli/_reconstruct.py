"""`fwid reconstruct`: raw tracking takes (and autopilot logs) to section-1 flights, with
`reconstruction.json` and one figure per take (CONTRACTS section 5)."""

from __future__ import annotations

import sys
import time
from pathlib import Path


def reconstruct(args) -> int:
    from .._errors import InputError

    t0 = time.perf_counter()
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a folder; give --out a folder")
    import fwid

    say = None if args.quiet else (lambda msg: print(f"fwid: {msg}", file=sys.stderr))
    result = fwid.reconstruct(args.raw, body=args.body, frame=args.frame, onboard=args.onboard,
                              clock_offset=args.clock_offset, max_dropout=args.max_dropout,
                              min_overlap=args.min_overlap, progress=say)
    written = fwid.write_reconstruction(result, out) if result.flights else []
    if result.flights and args.figures:
        from fwid.report import plot_reconstruction

        fig = None  # one figure, redrawn take after take
        for fl in result.flights:
            fig = plot_reconstruction(fl, path=out / f"{fl.name}.reconstruction.png", figure=fig)
    n = len(result.flights)
    print(f"fwid: reconstructed {n} of {n + len(result.failures)} takes into {out}/ "
          f"({len(written)} files, {time.perf_counter() - t0:.1f} s)")
    for path, msg in result.failures:
        print(f"fwid: error: {msg}", file=sys.stderr)
    return 2 if result.failures else 0
