"""`fwid reconstruct`: raw tracking takes (and autopilot logs) to section-1 flights, with
`reconstruction.json` and one figure per take (the raw-recording formats)."""

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
    from fwid.reconstruction import raw_files
    from fwid.reconstruction._read import distinct_names
    from fwid.reconstruction._workers import FIGURES, SCIPY, run_all, start

    rmap = None
    if args.recording_map is not None:
        from fwid.reconstruction import read_map

        rmap = read_map(args.recording_map)  # a bad map: one line before any work
    say = None if args.quiet else (lambda msg: print(f"fwid: {msg}", file=sys.stderr))
    # worker processes for the per-take work (reading, clocks, writing, figures)
    files = raw_files(args.raw, rmap)
    distinct_names(files)
    pool = start(len(files), preload=SCIPY + (FIGURES if args.figures else ()))
    try:
        result = fwid.reconstruct(args.raw, body=args.body, frame=args.frame,
                                  onboard=args.onboard, clock_offset=args.clock_offset,
                                  max_dropout=args.max_dropout, min_overlap=args.min_overlap,
                                  progress=say, pool=pool, recording_map=rmap,
                                  strict_frame=args.strict_frame,
                                  keep_ground=args.keep_ground)
        written = fwid.write_reconstruction(result, out, pool=pool) if result.flights else []
        if result.flights and args.figures:
            run_all(figure_file, [((fl, out / f"{fl.name}.reconstruction.png"), {})
                                  for fl in result.flights], pool)
    finally:
        if pool is not None:
            pool.shutdown()
    n = len(result.flights)
    k = len({fl.entry["source"] for fl in result.flights})  # a take may give several flights
    several = f" ({n} flights)" if n != k else ""
    print(f"fwid: reconstructed {k} of {len(files)} takes{several} into {out}/ "
          f"({len(written)} files, {time.perf_counter() - t0:.1f} s)")
    for path, msg in result.failures:
        print(f"fwid: error: {msg}", file=sys.stderr)
    return 2 if result.failures else 0


_FIGURE = {}


def figure_file(flight, path) -> None:
    """Draw a take's figure into `path`, redrawing this process's last figure (one
    `matplotlib` figure per process, reused take after take)."""
    from fwid.report import plot_reconstruction

    _FIGURE["fig"] = plot_reconstruction(flight, path=path, figure=_FIGURE.get("fig"))
