"""Timing, memory and the machine record, shared by `speed.py` and `profile_fit.py`."""

from __future__ import annotations

import json
import os
import platform
import resource
import statistics
import time
from pathlib import Path

import jax
import numpy as np

import fwid

from _problem import X64_BY_FWID
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)


def _rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def _device_peak():
    try:
        stats = jax.devices()[0].memory_stats()
        return None if not stats else stats.get("peak_bytes_in_use")
    except Exception:
        return None


def xla_memory(compiled):
    """Bytes of the compiled program's buffers: temporaries + arguments + outputs."""
    try:
        m = compiled.memory_analysis()
        return dict(temp=int(m.temp_size_in_bytes), arguments=int(m.argument_size_in_bytes),
                    outputs=int(m.output_size_in_bytes),
                    total=int(m.temp_size_in_bytes + m.argument_size_in_bytes
                              + m.output_size_in_bytes))
    except Exception:
        return None


def time_calls(call, repeats):
    """First call (compilation included) and `repeats` warm calls; `call` must block."""
    rss0, dev0 = _rss_mb(), _device_peak()
    t0 = time.perf_counter()
    out = call()
    first = time.perf_counter() - t0
    warm = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = call()
        warm.append(time.perf_counter() - t0)
    dev1 = _device_peak()
    mem = dict(rss_growth_mb=_rss_mb() - rss0)
    if dev0 is not None and dev1 is not None:
        mem["device_peak_bytes"] = int(dev1)
        mem["device_peak_growth_bytes"] = int(dev1 - dev0)
    return out, first, warm, mem


def block(tree):
    """Wait for a pytree of JAX arrays and bring it to numpy."""
    return jax.tree_util.tree_map(np.asarray, jax.block_until_ready(tree))


def warm_times(fn, *a, repeats=15):
    """(median, min) wall time of warm calls: with other work on the machine the minimum is
    the steadier estimate of what the code itself costs."""
    jax.block_until_ready(fn(*a))
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*a))
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), min(ts)


def interleaved(calls: dict, rounds: int) -> dict:
    """Every call of `calls` (name -> no-argument function) once per round, round-robin, so
    that all see the same load, after one warm-up call each: per name the median, the
    minimum and every time [s]."""
    for f in calls.values():
        f()
    times = {k: [] for k in calls}
    for _ in range(rounds):
        for k, f in calls.items():
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return {k: dict(median_s=statistics.median(v), min_s=min(v), all_s=v)
            for k, v in times.items()}


def aot(fn, *a):
    """`jax.jit(fn)` compiled ahead of time for `a`: (compiled, trace+lower s, compile s)."""
    t0 = time.perf_counter()
    lowered = jax.jit(fn).lower(*a)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2 = time.perf_counter()
    return compiled, t1 - t0, t2 - t1


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:
        return None


def machine(load0):
    """The machine, JAX and versions; `load0` the load average when the run started."""
    return dict(
        platform=platform.platform(), processor=platform.processor(),
        python=platform.python_version(), cpu_count=os.cpu_count(),
        cpus_usable=len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        loadavg_start=load0, loadavg_end=os.getloadavg(),
        jax=jax.__version__, jax_backend=jax.default_backend(),
        devices=[str(d) for d in jax.devices()],
        device_kind=jax.devices()[0].device_kind,
        float64=dict(enabled=bool(jax.config.jax_enable_x64), enabled_by_importing_fwid=X64_BY_FWID,
                     FWID_NO_X64=os.environ.get("FWID_NO_X64")),
        compilation_cache_dir=jax.config.jax_compilation_cache_dir,
        fwid_path=str(Path(fwid.__file__).parent),
        XLA_FLAGS=os.environ.get("XLA_FLAGS"),
        versions={m: _version(m) for m in ("diffrax", "optimistix", "equinox", "lineax",
                                            "numpy", "scipy", "fwid")},
    )


def machine_line(mc, script):
    """The Markdown sentence on the machine, for the tables' heading."""
    f64 = mc["float64"]
    by = "importing fwid" if f64["enabled_by_importing_fwid"] else script
    return (f"Machine: {mc['platform']}, {mc['cpu_count']} CPUs ({mc['cpus_usable']} usable), "
            f"JAX {mc['jax']} on **{mc['jax_backend']}** ({mc['device_kind']}); float64 "
            f"{'on' if f64['enabled'] else 'OFF'} (jax_enable_x64, set by {by}); "
            f"load average {mc['loadavg_start'][0]:.1f} at start, "
            f"{mc['loadavg_end'][0]:.1f} at end.")


def print_backend():
    print(f"fwid from {Path(fwid.__file__).parent}; JAX {jax.__version__} on "
          f"{jax.default_backend()}: {', '.join(str(d) for d in jax.devices())}", flush=True)


def _jsonable(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def write(res, out, md):
    """`res` as JSON to `out`, the Markdown `md` next to it (`.md`), and print `md`."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(_provenance.json_text(res, indent=1, default=_jsonable))
    out.with_suffix(".md").write_text(_provenance.markdown(md))
    print()
    print(md)
    print(f"wrote {out} and {out.with_suffix('.md')}")
