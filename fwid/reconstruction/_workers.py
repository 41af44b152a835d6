"""Per-take work in worker processes: reading the takes, aligning the clocks, writing the
flights and drawing their figures run one take per task on `min(cores, takes)` processes,
while the smoother (JAX, one device per core) runs in the calling process.

The workers are forked when the pool starts, which must be before JAX is imported (a
process that runs JAX's threads cannot be forked safely): `fwid reconstruct` starts them
first thing; where JAX is already imported (a notebook, a test) everything runs in the
calling process. So are one core and fewer than `MIN_TAKES` takes (a worker costs about
as much to start as one take's work). A task's `fwid.FwidError` comes back as its result
(`Failed`), not raised, so that a bad take never stops the others.
"""

from __future__ import annotations

import importlib
import os
from typing import NamedTuple

from .._errors import FwidError

#: Fewest takes for which workers are started.
MIN_TAKES = 4
#: Most worker processes.
MAX_WORKERS = 8
#: What the clock alignment imports (`_clock`).
SCIPY = ("scipy.interpolate", "scipy.optimize", "scipy.signal")
#: What drawing the figures imports (`fwid.report._reconstruction`).
FIGURES = ("fwid.report._reconstruction", "matplotlib.backends.backend_agg")


class Failed(NamedTuple):
    """A task's `fwid.FwidError`, as its one-line message."""

    message: str


def cores() -> int:
    """The CPU cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def start(takes: int, processes: int | None = None, preload=SCIPY):
    """A process pool for `takes` takes, or None where the work should stay in this process.

    **Arguments:**
    - `takes`: the number of takes;
    - `processes`: the workers wanted (default: one per core, at most `MAX_WORKERS`); 0 or 1:
      none;
    - `preload`: modules the tasks need, imported here before the workers are forked (once,
      not once per worker).

    **Returns:** a `concurrent.futures.ProcessPoolExecutor` (shut it down after use: its
    workers' CPU time then counts as this process's children's), or None.
    """
    n = min(cores(), MAX_WORKERS) if processes is None else int(processes)
    n = min(n, takes)
    if n < 2 or (processes is None and takes < MIN_TAKES):
        return None
    import multiprocessing
    import sys
    from concurrent.futures import ProcessPoolExecutor

    if "jax" in sys.modules or "fork" not in multiprocessing.get_all_start_methods():
        return None
    for m in preload:
        importlib.import_module(m)
    pool = ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork"))
    pool.submit(int)  # forks the workers now, before anything imports JAX
    return pool


def _guarded(task):
    fn, args, kwargs = task
    try:
        return fn(*args, **kwargs)
    except FwidError as e:
        return Failed(str(e))


def run_all(fn, tasks, pool=None, meanwhile=None) -> list:
    """`fn(*args, **kwargs)` for each `(args, kwargs)` of `tasks`, in order, on the pool's
    workers (or here without one); a task's `fwid.FwidError` is returned as a `Failed`.
    `meanwhile()`, if given, runs here while the workers work (not at all without them)."""
    jobs = [(fn, tuple(a), dict(k)) for a, k in tasks]
    if pool is None or len(jobs) < 2:
        return [_guarded(j) for j in jobs]
    results = pool.map(_guarded, jobs)  # submitted now
    if meanwhile is not None:
        meanwhile()
    return list(results)
