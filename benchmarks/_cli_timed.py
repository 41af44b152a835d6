"""`fwid identify ARGS` as a user runs it, with where the time goes: run as a process by
`_shared.py` (`python benchmarks/_cli_timed.py identify FOLDER --model lon --out DIR`).

Prints one JSON line: `import` (JAX, diffrax, matplotlib and fwid's stages), `compile`
(tracing, lowering and XLA compilation or loading from the persistent cache, from JAX's
monitoring events; each in `compile_parts`), `fit` (`fwid.identify` less its compilations), `figures`, `reports`
(the JSON and CSV report, the terminal summary), `compiles` (XLA compilations, not counting
the programs loaded from the persistent cache) and `cache_hits`. The process's own start-up
is the outside wall time less these.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's fwid

T = {"import": 0.0, "compile": 0.0, "fit": 0.0, "figures": 0.0, "reports": 0.0}
N = {"compiles": 0, "cache_hits": 0}
COMPILE_EVENTS = {"/jax/core/compile/jaxpr_trace_duration": "trace",
                  "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower",
                  "/jax/core/compile/backend_compile_duration": "xla"}
PARTS = dict.fromkeys(COMPILE_EVENTS.values(), 0.0)  # compile = trace + lower + xla


def _timed(owner, name, part):
    fn = getattr(owner, name)

    def wrapper(*a, **kw):
        t0, c0 = time.perf_counter(), T["compile"]
        try:
            return fn(*a, **kw)
        finally:  # the compilations inside count as compile, not as this part
            T[part] += time.perf_counter() - t0 - (T["compile"] - c0)

    setattr(owner, name, wrapper)


def main(argv):
    t0 = time.perf_counter()
    from fwid.cli import executable_setup

    executable_setup()  # as the `fwid` executable does, before Equinox is imported
    import jax
    import jax.monitoring

    import fwid
    import fwid.identification  # noqa: F401
    import fwid.report
    from fwid.cli import main as cli

    T["import"] = time.perf_counter() - t0

    def on_duration(event, secs, **_):
        if event in COMPILE_EVENTS:
            T["compile"] += secs
            PARTS[COMPILE_EVENTS[event]] += secs
        N["compiles"] += event == "/jax/core/compile/backend_compile_duration"

    def on_event(event, **_):
        N["cache_hits"] += event == "/jax/compilation_cache/cache_hits"

    jax.monitoring.register_event_duration_secs_listener(on_duration)
    jax.monitoring.register_event_listener(on_event)
    for name in ("identify", "identify_flapping_model", "identify_combined", "compare_joint"):
        _timed(fwid, name, "fit")
    for name in ("plot_flight_fit", "plot_poles", "plot_time_and_spectrum",
                 "plot_superposition", "plot_steady_vs_manoeuvre"):
        _timed(fwid, name, "figures")
    _timed(fwid.report, "plot_fits_overview", "figures")
    for name in ("identification_report", "write_json"):
        _timed(fwid, name, "reports")
    for name in ("write_text", "identification_summary"):
        _timed(fwid.report, name, "reports")
    rc = cli(argv)
    N["compiles"] -= N["cache_hits"]  # a program loaded from the cache is no compilation
    print(json.dumps({"rc": rc, **T, **N, "compile_parts": PARTS}))


if __name__ == "__main__":
    main(sys.argv[1:])
