"""The helpers the benchmark scripts share: timing, memory and the machine record (`speed.py`,
`profile_fit.py`, `simd.py`); the three timed methods of the speed problem (fwid, the scipy
peer, the JAX reference) and their agreement; the whole-process row of `speed.py --process`.

**Timed methods.** 1. **fwid**: `fwid.fit` on one flight; for N flights, N *independent* fits in one batched
   call, `fwid.fit_each`. Where fwid has no `fit_each` (older versions), or the flights start
   from different values (`--start least-squares`), fwid's internal pure estimator
   `fwid.estimate._output_error._fit_batch` is vmapped over a leading flight axis instead
   (each flight a batch of one, fwid.fit's default settings read from its signature).
2. **scipy**: `peers/scipy_output_error.py` (numpy RK4 + `scipy.optimize.least_squares`, finite
   differences), one flight per call.
3. **JAX reference**: `peers/jax_output_error.py` (`lax.scan` RK4, jacfwd, hand-written
   Gauss-Newton with step halving, R relaxed every iteration), `vmap` for batches.

**Whole process.** The whole-process row of `speed.py` (`--process`): `fwid identify FOLDER --model lon --out
DIR` as a user runs it from a shell, on 1, 16 and 64 simulated flights, cold (an empty
compilation cache folder) and warm (a second process on the same folder), against the scipy
baseline (numpy RK4 + `scipy.optimize.least_squares`, `peers/scipy_output_error.py`) timed in the same run,
with where the time goes (`_cli_timed.py`: import, compile, fit, figures, reports).

The scipy time for N flights is its measured mean per fit on the benchmark problem's flights
(`cases/delfly_speed.py`, same model, length and step as `fwid simulate`'s) times N, marked
extrapolated beyond the flights timed; it counts no process start-up, no reading of the
files and no report (in scipy's favour).
"""

from __future__ import annotations

import inspect
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import fwid
from fwid.estimate import _each
from fwid.estimate import _output_error as _oe
from fwid.simulation import stack_experiments

from cases.delfly_speed import AERO, DT, NAMES, X64_BY_FWID, experiment, lon_f_jax, make_lon_f_numpy
from peers.jax_output_error import make_fit
from peers.scipy_output_error import fit_output_error

import _provenance

HERE = Path(__file__).resolve().parent
PARTS = ("import", "compile", "fit", "figures", "reports")


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


def run_and_write(run, markdown, args):
    """A benchmark's main: the backend printed, `run(args)`, its JSON to `args.out` and its
    `markdown(res)` beside it."""
    print_backend()
    res = run(args)
    write(res, args.out, markdown(res))


def write(res, out, md):
    """`res` as JSON to `out`, the Markdown `md` next to it (`.md`), and print `md`."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(_provenance.json_text(res, indent=1, default=_jsonable))
    out.with_suffix(".md").write_text(_provenance.markdown(md))
    print()
    print(md)
    print(f"wrote {out} and {out.with_suffix('.md')}")


# fwid's internal estimator changed signature while this benchmark was written; follow both.
_FIT_BATCH_TAKES_SCALE = "scale" in inspect.signature(_oe._fit_batch).parameters
# the reference's settings (make_fit's defaults), recorded with the results
REFERENCE_SETTINGS = dict(max_iter=50, max_halvings=10, cost_rtol=1e-10, step_tol=1e-9)


class Bench:
    """The three methods on `flights` (from `_problem.make_flights`), each flight started from
    its row of `starts` (n, 16)."""

    def __init__(self, flights, starts):
        self.F = flights
        self.starts = starts  # (n, 16)
        self.model = fwid.longitudinal()
        assert tuple(self.model.free) == NAMES, self.model.free
        self.exps = [experiment(flights, i) for i in range(len(starts))]
        self.fwid_alone = {}  # flight -> (theta, std_cr, info) from fwid.fit on that flight alone
        sig = inspect.signature(fwid.fit).parameters
        self.fit_defaults = dict(
            diagonal=(sig["noise"].default == "diagonal"),
            max_passes=sig["max_passes"].default, max_steps=sig["max_steps"].default,
            rtol=sig["rtol"].default, cost_rtol=sig["cost_rtol"].default,
        )
        self._fwid_batched = None
        self._start_models = {}
        self.ref = make_fit(lon_f_jax, **REFERENCE_SETTINGS)  # (fit_one, fit_many)

    # -- fwid.fit, one flight per call -----------------------------------------------------
    def _start_model(self, i):
        # built once per flight, as the reference's start arrays are
        if i not in self._start_models:
            self._start_models[i] = self.model.with_params(
                dict(zip(NAMES, map(float, self.starts[i]))))
        return self._start_models[i]

    def fwid_fit(self, i):
        r = fwid.fit(self.model, self.exps[i], start=self._start_model(i))
        theta, std = block((r.theta, r.std_cr))
        info = dict(passes=int(r.passes), steps=int(r.steps), converged=bool(r.converged))
        self.fwid_alone[i] = (theta, std, info)
        return theta

    def fwid_fit_xla_memory(self, i=0):
        """The XLA buffers of the program fwid.fit runs (its filter_jit, already compiled)."""
        try:
            sm, a = self.fit_batch_args(i)
            if hasattr(_oe, "_fit_one_jit"):  # fwid.fit's program for a single flight
                lowered = _oe._fit_one_jit.lower(sm, a[0], self.exps[i], n_local_batch=0,
                                                 **self.fit_defaults)
            else:
                lowered = _oe._fit_batch_jit.lower(sm, *a, n_local_batch=0, **self.fit_defaults)
            return xla_memory(lowered.lowered.compile())
        except Exception:
            return None

    # -- fwid, N independent fits in one vmapped call --------------------------------------
    def fwid_batched_fn(self):
        if self._fwid_batched is None:
            model, kw = self.model, self.fit_defaults
            if _FIT_BATCH_TAKES_SCALE:  # older fwid: _fit_batch(model, s0, scale, batch, ...)
                def one(theta0, batch):
                    scale = jnp.where(jnp.abs(theta0) > 0, jnp.abs(theta0), 1.0)
                    out = _oe._fit_batch(model, theta0 / scale, scale, batch, n_local_batch=0,
                                         **kw)
                    return {**out, "theta": out["s"] * scale}
            else:  # fwid now: _fit_batch(model, theta0, batch, ...), scaling inside
                def one(theta0, batch):
                    return _oe._fit_batch(model, theta0, batch, n_local_batch=0, **kw)

            self._fwid_batched = jax.jit(jax.vmap(one))
        return self._fwid_batched

    def fwid_batched_args(self, n):
        theta0 = jnp.asarray(self.starts[:n])
        batches = [stack_experiments([e]) for e in self.exps[:n]]  # as fwid.fit does
        batch = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *batches)
        return theta0, batch

    @property
    def use_fit_each(self):
        """`fwid.fit_each` takes one start for all flights: usable when the starts agree."""
        return hasattr(fwid, "fit_each") and bool(np.all(self.starts == self.starts[0]))

    @property
    def batched_label(self):
        return "fwid.fit_each" if self.use_fit_each else "fwid vmap(_fit_batch)"

    def fwid_batched(self, n):
        """A call that fits flights 0..n-1 independently in one batched fwid call and returns
        `(theta (n, p), cramer_rao_std (n, p), info)`."""
        if self.use_fit_each:
            exps, sm = self.exps[:n], self._start_model(0)

            def call():
                rs = fwid.fit_each(self.model, exps, start=sm)
                theta, std = block((jnp.stack([r.theta for r in rs]),
                                     jnp.stack([r.std_cr for r in rs])))
                return theta, std, dict(passes_max=max(int(r.passes) for r in rs),
                                        steps=[int(r.steps) for r in rs],
                                        all_converged=all(bool(r.converged) for r in rs))
        else:
            fb, a = self.fwid_batched_fn(), self.fwid_batched_args(n)

            def call():
                out = block(fb(*a))
                return (out["theta"], np.sqrt(np.diagonal(out["cov_cr"], axis1=-2, axis2=-1)),
                        dict(passes_max=int(out["passes"].max()), steps=out["steps"].tolist(),
                             all_converged=bool(out["converged"].all())))
        return call

    def fwid_batched_xla_memory(self, n):
        try:
            if self.use_fit_each:
                theta0s = jnp.stack([self._start_model(0).theta()] * n)
                nmax = max(e.n for e in self.exps[:n])
                stacked = jax.tree_util.tree_map(
                    lambda *a: jnp.stack(a), *[stack_experiments([e], n=nmax) for e in self.exps[:n]])
                lowered = _each._fit_each_batched.lower(self.model, theta0s, stacked,
                                                        n_local_batch=0, **self.fit_defaults)
                return xla_memory(lowered.lowered.compile())
            return xla_memory(self.fwid_batched_fn().lower(*self.fwid_batched_args(n)).compile())
        except Exception:
            return None

    def fit_batch_args(self, i=0):
        """The arguments fwid.fit gives `_fit_batch` for flight i alone (positional part)."""
        sm = self._start_model(i)
        theta0 = sm.theta()
        batch = stack_experiments([self.exps[i]])
        if _FIT_BATCH_TAKES_SCALE:
            scale = jnp.where(jnp.abs(theta0) > 0, jnp.abs(theta0), 1.0)
            return sm, (theta0 / scale, scale, batch)
        return sm, (theta0, batch)

    # -- JAX reference ---------------------------------------------------------------------
    def ref_args(self, n):
        F = self.F
        return (jnp.asarray(self.starts[:n]), jnp.asarray(F["u"][:n]), jnp.asarray(F["z"][:n]),
                jnp.asarray(F["x0"][:n]), jnp.full(n, DT),
                {k: jnp.asarray(v[:n]) for k, v in F["consts"].items()})

    def ref_args_one(self):
        """`ref_args(1)` without the flight axis: the arguments of the reference's `fit_one`."""
        return [x[0] if not isinstance(x, dict) else {k: v[0] for k, v in x.items()}
                for x in self.ref_args(1)]

    # -- scipy -----------------------------------------------------------------------------
    def scipy_fit(self, i, max_outer=50):
        F = self.F
        f = make_lon_f_numpy(F["consts_list"][i])
        return fit_output_error(f, self.starts[i], [F["t"]], [F["u"][i]], [F["z"][i]],
                                [F["x0"][i]], rtol=self.fit_defaults["cost_rtol"],
                                max_outer=max_outer)

    def settings(self):
        """The settings of the three methods, for the results' JSON."""
        return dict(
            fwid_fit_settings=self.fit_defaults,
            scipy_settings=dict(rtol=self.fit_defaults["cost_rtol"], method="trf",
                                jac="2-point"),
            reference_settings=REFERENCE_SETTINGS,
        )


def agreement(theta, theta_fwid, std_fwid):
    """Largest relative difference of the 12 aero parameters, and in Cramer-Rao stds."""
    a = slice(0, len(AERO))
    d = np.abs(theta[..., a] - theta_fwid[..., a])
    return dict(max_rel_diff_aero=float(np.max(d / np.abs(theta_fwid[..., a]))),
                max_diff_in_std_aero=float(np.max(d / std_fwid[..., a])))




def cli_process(folder: Path, out: Path, cache: Path, figures: str = "summary") -> dict:
    """One `fwid identify` process, timed from outside, with its breakdown."""
    env = {**os.environ, "FWID_JAX_CACHE": str(cache)}
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(HERE / "_cli_timed.py"), "identify", str(folder),
                           "--model", "lon", "--out", str(out), "--quiet", "--figures", figures],
                          env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"fwid identify failed: {proc.stderr[-2000:]}")
    parts = json.loads(proc.stdout.strip().splitlines()[-1])
    parts["other"] = wall - sum(parts[k] for k in PARTS)
    return {"wall_s": wall, **parts}


def scipy_per_fit(n_fits: int, seed: int) -> dict:
    """The scipy baseline's mean time per flight, over `n_fits` flights of the problem."""
    from cases.delfly_speed import setup

    F, starts, _ = setup(n_fits, seed, "true1.2")
    bench = Bench(F, starts)
    times = []
    for i in range(n_fits):
        t0 = time.perf_counter()
        bench.scipy_fit(i)
        times.append(time.perf_counter() - t0)
    return {"per_fit_s": sum(times) / len(times), "fits_timed": n_fits, "times_s": times}


def run_process(sizes, scipy_fits: int, seed: int) -> dict:
    from fwid.synth import write_flights

    rows = []
    with tempfile.TemporaryDirectory(prefix="fwid-process-") as tmp:
        tmp = Path(tmp)
        for n in sizes:
            folder = tmp / f"flights_{n}"
            write_flights(folder, n_flights=n, axis="lon", seed=seed)
            cache = tmp / f"cache_{n}"  # empty: cold
            for state in ("cold", "warm"):
                r = cli_process(folder, tmp / f"out_{n}_{state}", cache)
                rows.append({"flights": n, "cache": state, **r})
                print(f"fwid identify, {n} flights, {state}: {r['wall_s']:.1f} s "
                      f"({', '.join(f'{k} {r[k]:.1f}' for k in (*PARTS, 'other'))}; "
                      f"{r['compiles']} compilations)", flush=True)
    scipy = scipy_per_fit(scipy_fits, seed)
    print(f"scipy baseline: {scipy['per_fit_s']:.1f} s a fit ({scipy_fits} timed)", flush=True)
    for r in rows:
        r["scipy_s"] = scipy["per_fit_s"] * r["flights"]
        r["scipy_extrapolated"] = r["flights"] > scipy_fits
        r["speedup_vs_scipy"] = r["scipy_s"] / r["wall_s"]
    return {"rows": rows, "scipy": scipy}


def process_markdown(res, machine_line_: str) -> str:
    lines = ["# Whole process: `fwid identify FOLDER --model lon --out DIR` from a shell", "",
             machine_line_, "",
             "Cold: an empty compilation cache folder; warm: a second process on it. "
             "Seconds; the parts from `benchmarks/_cli_timed.py` (compile: tracing, lowering, "
             "XLA compilation or cache loading; other: the interpreter, reading the flights and "
             "the rest; the tracing of nested jits overlaps, so compile is an upper bound and "
             "fit a lower one). "
             "scipy: numpy RK4 + `least_squares`, its mean time per fit in this run times the "
             "flights (* extrapolated), without process start-up or reports.", "",
             "| flights | cache | whole process | import | compile | fit | figures | reports "
             "| other | XLA compilations | scipy | fwid faster by |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in res["rows"]:
        star = "*" if r["scipy_extrapolated"] else ""
        lines.append(
            f"| {r['flights']} | {r['cache']} | {r['wall_s']:.1f} | "
            + " | ".join(f"{r[k]:.1f}" for k in (*PARTS, "other"))
            + f" | {r['compiles']} | {r['scipy_s']:.0f}{star} | {r['speedup_vs_scipy']:.1f}x |")
    return "\n".join(lines) + "\n"
