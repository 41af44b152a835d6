"""Speed benchmark: fwid's output-error fit against a scipy baseline and a hand-written JAX loop.

    python benchmarks/speed.py --out benchmarks/results/speed.json [--sizes 1,4,16,64,256]
                               [--quick] [--profile]

The same fits, in the same run, by three methods:

1. **fwid**: `fwid.fit` on one flight; for N flights, N *independent* fits in one batched
   call, `fwid.fit_each`. Where fwid has no `fit_each` (older versions), or the flights start
   from different values (`--start least-squares`), the benchmark vmaps fwid's internal pure
   estimator `fwid.estimate._output_error._fit_batch` over a leading flight axis instead (each
   flight a batch of one, fwid.fit's default settings read from its signature). The batched
   estimates are checked against `fwid.fit` on each flight alone (rows "fwid.fit loop";
   identical means within 1e-9 relative).
2. **scipy**: `benchmarks/_baseline.py` (numpy RK4 + `scipy.optimize.least_squares`, finite
   differences), a Python loop over flights. Only a subset of flights is timed; for larger N
   the time is the measured mean per flight times N, marked *extrapolated*.
3. **JAX reference**: `benchmarks/_jax_reference.py` (`lax.scan` RK4, jacfwd, hand-written
   Gauss-Newton with step halving, R relaxed every iteration), `vmap` for batches: the
   practical speed limit of the problem in JAX.

Problem: simulated DelFly longitudinal flights (Eq. 7 with the four bias terms, 16 free
parameters), 4.5 s at 200 Hz (900 samples), elevator 3211 (even flights) or doublet (odd
flights), white Gaussian measurement noise on all four states; every method starts from the
same values (true x 1.2 by default). Flight i is the same at every size.

Reported per method and size: warm wall time (median of repeats after a warm-up), compile
time (first call minus warm), fits per second, speed-up over scipy, peak memory (tracemalloc
for scipy; for JAX the compiled program's XLA buffers, the growth of the process's peak RSS,
and on GPU the device's peak bytes), and the largest relative difference of the 12 aero
parameters from fwid (and in Cramer-Rao standard deviations). `--profile` adds where fwid's
time goes (simulation and Jacobian through diffrax vs a scan, Gauss-Newton steps per
relaxation pass, accepted vs rejected) and a few what-if timings made by patching fwid's
internals *in this process only* (fwid's files are not touched).

`--quick` (sizes 1 and 4, fewer repeats, one scipy fit) is meant to finish in under three
minutes on a 2-core CPU. The machine is recorded in the JSON; on a GPU everything JAX runs
there unchanged (`jax.default_backend()`), scipy on the host CPU.
"""

from __future__ import annotations

import argparse
import functools
import inspect
import json
import os
import platform
import resource
import statistics
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))  # the fwid of this checkout, not another installed one

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import fwid  # noqa: E402  (turns on float64 unless FWID_NO_X64 is set)

X64_BY_FWID = bool(jax.config.jax_enable_x64)
jax.config.update("jax_enable_x64", True)  # fwid.fit needs float64; say so in the output

from fwid.estimate import _output_error as _oe  # noqa: E402
from fwid.models import TABLE1  # noqa: E402
from fwid.simulate import stack_experiments  # noqa: E402

from _baseline import fit_output_error  # noqa: E402
from _jax_reference import make_fit, rk4_scan  # noqa: E402

# fwid's internal estimator changed signature while this benchmark was written; follow both.
_FIT_BATCH_TAKES_SCALE = "scale" in inspect.signature(_oe._fit_batch).parameters

# --------------------------------------------------------------------------------------------
# The problem
# --------------------------------------------------------------------------------------------
DT = 0.005  # 200 Hz
N_SAMPLES = 900  # 4.5 s
AERO = tuple(TABLE1)  # Xq Xu Xw Xde Zq Zu Zw Zde Mq Mu Mw Mde
BIASES = ("bq", "bu", "bw", "btheta")
NAMES = AERO + BIASES
TRUE = dict(TABLE1, bq=0.02, bu=-0.01, bw=0.015, btheta=-0.005)
NOISE_STD = (0.02, 0.005, 0.005, 0.002)  # q [rad/s], u [m/s], w [m/s], theta [rad]
# A plausible DelFly II: mass [kg], pitch inertia [kg m^2], trim u0, w0 [m/s], theta0 [rad].
DELFLY = dict(mass=0.0205, Iy=1.3e-4, g=9.81, u0=0.8, w0=0.3, theta0=1.2)
CONST_KEYS = ("mass", "Iy", "g", "u0", "w0", "theta0")


def vehicle_constants():
    """`fwid.synth.DELFLY` when fwid has one (with the keys this model needs), else ours."""
    try:
        import fwid.synth as synth

        d = synth.DELFLY
        vals = {k: float(d[k] if isinstance(d, dict) else getattr(d, k)) for k in CONST_KEYS}
        return vals, "fwid.synth.DELFLY"
    except Exception:
        return dict(DELFLY), "benchmarks/speed.py DELFLY (fwid.synth.DELFLY not available)"


def lon_f_jax(x, u, th, c):
    """Eq. (7) with Eqs. (1), (3), (5) and the biases, written out again (no fwid)."""
    q, uu, w, tt = x[0], x[1], x[2], x[3]
    de = u[0]
    Xq, Xu, Xw, Xde, Zq, Zu, Zw, Zde, Mq, Mu, Mw, Mde, bq, bu, bw, bt = (th[i] for i in range(16))
    X = Xq * q + Xu * uu + Xw * w + Xde * de
    Z = Zq * q + Zu * uu + Zw * w + Zde * de
    M = Mq * q + Mu * uu + Mw * w + Mde * de
    return jnp.stack([
        M / c["Iy"] + bq,
        X / c["mass"] - c["w0"] * q - c["g"] * jnp.cos(c["theta0"]) * tt + bu,
        Z / c["mass"] + c["u0"] * q - c["g"] * jnp.sin(c["theta0"]) * tt + bw,
        q + bt,
    ])


def make_lon_f_numpy(c):
    """The same equations in numpy for the scipy baseline, `f(x, u, theta)`."""
    m, Iy, g, u0, w0 = c["mass"], c["Iy"], c["g"], c["u0"], c["w0"]
    ct, st = np.cos(c["theta0"]), np.sin(c["theta0"])

    def f(x, u, th):
        q, uu, w, tt = x
        de = u[0]
        Xq, Xu, Xw, Xde, Zq, Zu, Zw, Zde, Mq, Mu, Mw, Mde, bq, bu, bw, bt = th
        X = Xq * q + Xu * uu + Xw * w + Xde * de
        Z = Zq * q + Zu * uu + Zw * w + Zde * de
        M = Mq * q + Mu * uu + Mw * w + Mde * de
        return np.array([M / Iy + bq, X / m - w0 * q - g * ct * tt + bu,
                         Z / m + u0 * q - g * st * tt + bw, q + bt])

    return f


def elevator(t, kind, amp, pulse, t_on):
    """A 3211 (pulse widths 3-2-1-1 x `pulse`) or a doublet (2-2 x `pulse`), in rad."""
    pattern = [(3, 1), (2, -1), (1, 1), (1, -1)] if kind == "3211" else [(2, 1), (2, -1)]
    de = np.zeros_like(t)
    start = t_on
    for width, sign in pattern:
        end = start + width * pulse
        de[(t >= start - 1e-12) & (t < end - 1e-12)] = sign * amp
        start = end
    return de


def make_flights(n, seed, consts):
    """`n` simulated flights; flight i depends only on (seed, i)."""
    t = np.arange(N_SAMPLES) * DT
    theta_true = np.array([TRUE[k] for k in NAMES])
    us, x0s, cs, kinds = [], [], [], []
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        kind = "3211" if i % 2 == 0 else "doublet"
        amp = rng.uniform(0.05, 0.09) * (1 if rng.uniform() < 0.5 else -1)
        pulse = rng.uniform(0.15, 0.22)
        us.append(elevator(t, kind, amp, pulse, rng.uniform(0.3, 0.8))[:, None])
        x0s.append(np.zeros(4) if i == 0 else rng.normal(0.0, [0.05, 0.01, 0.01, 0.01]))
        c = dict(consts)
        if i > 0:  # trims differ a little from flight to flight
            c.update(u0=consts["u0"] * (1 + 0.05 * rng.normal()),
                     w0=consts["w0"] * (1 + 0.05 * rng.normal()),
                     theta0=consts["theta0"] + 0.03 * rng.normal())
        cs.append(c)
        kinds.append(kind)
    U, X0 = np.stack(us), np.stack(x0s)
    C = {k: np.array([c[k] for c in cs]) for k in CONST_KEYS}
    sim = jax.jit(jax.vmap(lambda u, x0, c: rk4_scan(lon_f_jax, jnp.asarray(theta_true), x0, u,
                                                      DT, c)))
    X = np.asarray(sim(jnp.asarray(U), jnp.asarray(X0), {k: jnp.asarray(v) for k, v in C.items()}))
    Z = np.empty_like(X)
    for i in range(n):
        rng = np.random.default_rng([seed, i, 1])
        Z[i] = X[i] + rng.normal(size=X[i].shape) * np.asarray(NOISE_STD)
    return dict(t=t, u=U, z=Z, x0=X0, consts=C, kinds=kinds, theta_true=theta_true,
                consts_list=cs)


# --------------------------------------------------------------------------------------------
# Measuring
# --------------------------------------------------------------------------------------------
def _rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def _device_peak():
    try:
        stats = jax.devices()[0].memory_stats()
        return None if not stats else stats.get("peak_bytes_in_use")
    except Exception:
        return None


def _xla_memory(compiled):
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


def _block(tree):
    return jax.tree_util.tree_map(np.asarray, jax.block_until_ready(tree))


# --------------------------------------------------------------------------------------------
# The three methods
# --------------------------------------------------------------------------------------------
class Bench:
    def __init__(self, flights, starts, repeats):
        self.F = flights
        self.starts = starts  # (n, 16)
        self.repeats = repeats
        self.model = fwid.longitudinal()
        assert tuple(self.model.free) == NAMES, self.model.free
        self.exps = [
            fwid.Experiment(flights["t"], flights["u"][i], flights["z"][i], flights["x0"][i],
                            flights["consts_list"][i])
            for i in range(len(starts))
        ]
        self.fwid_alone = {}  # flight -> (theta, std_cr, info) from fwid.fit on that flight alone
        sig = inspect.signature(fwid.fit).parameters
        self.fit_defaults = dict(
            diagonal=(sig["noise"].default == "diagonal"),
            max_passes=sig["max_passes"].default, max_steps=sig["max_steps"].default,
            rtol=sig["rtol"].default, cost_rtol=sig["cost_rtol"].default,
        )
        self._fwid_batched = None
        self._start_models = {}
        self._ref = make_fit(lon_f_jax)

    # -- fwid.fit, one flight per call -----------------------------------------------------
    def _start_model(self, i):
        # built once per flight, as the reference's start arrays are
        if i not in self._start_models:
            self._start_models[i] = self.model.with_params(
                dict(zip(NAMES, map(float, self.starts[i]))))
        return self._start_models[i]

    def fwid_fit(self, i):
        r = fwid.fit(self.model, self.exps[i], start=self._start_model(i))
        theta, std = _block((r.theta, r.std_cr))
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
            return _xla_memory(lowered.lowered.compile())
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
                theta, std = _block((jnp.stack([r.theta for r in rs]),
                                     jnp.stack([r.std_cr for r in rs])))
                return theta, std, dict(passes_max=max(int(r.passes) for r in rs),
                                        steps=[int(r.steps) for r in rs],
                                        all_converged=all(bool(r.converged) for r in rs))
        else:
            fb, a = self.fwid_batched_fn(), self.fwid_batched_args(n)

            def call():
                out = _block(fb(*a))
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
                lowered = _oe._fit_each_batched.lower(self.model, theta0s, stacked,
                                                      n_local_batch=0, **self.fit_defaults)
                return _xla_memory(lowered.lowered.compile())
            return _xla_memory(self.fwid_batched_fn().lower(*self.fwid_batched_args(n)).compile())
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

    # -- scipy -----------------------------------------------------------------------------
    def scipy_fit(self, i, max_outer=50):
        F = self.F
        f = make_lon_f_numpy(F["consts_list"][i])
        return fit_output_error(f, self.starts[i], [F["t"]], [F["u"][i]], [F["z"][i]],
                                [F["x0"][i]], rtol=self.fit_defaults["cost_rtol"],
                                max_outer=max_outer)


def _agreement(theta, theta_fwid, std_fwid):
    """Largest relative difference of the 12 aero parameters, and in Cramer-Rao stds."""
    a = slice(0, len(AERO))
    d = np.abs(theta[..., a] - theta_fwid[..., a])
    return dict(max_rel_diff_aero=float(np.max(d / np.abs(theta_fwid[..., a]))),
                max_diff_in_std_aero=float(np.max(d / std_fwid[..., a])))


def run(args):
    sizes = sorted({1} | {int(s) for s in args.sizes.split(",")})  # N=1 is every ratio's base
    n_max = max(sizes)
    consts, consts_source = vehicle_constants()
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    F = make_flights(n_max, args.seed, consts)
    if args.start == "true1.2":
        starts = np.tile(1.2 * F["theta_true"], (n_max, 1))
    else:  # least-squares (equation error) start of each flight, by fwid
        m = fwid.longitudinal()
        starts = np.stack([
            np.asarray(fwid.least_squares_start(m, [fwid.Experiment(
                F["t"], F["u"][i], F["z"][i], F["x0"][i], F["consts_list"][i])]).theta())
            for i in range(n_max)])
    B = Bench(F, starts, args.repeats)
    print(f"fwid from {Path(fwid.__file__).parent}; JAX {jax.__version__} on "
          f"{jax.default_backend()}: {', '.join(str(d) for d in jax.devices())}", flush=True)
    rows = []
    fwid_est = {}  # n -> (theta (n,16), std (n,16)) from the fwid row of that size
    log = functools.partial(print, flush=True)

    def row(method, n, warm, first=None, **kw):
        w = statistics.median(warm) if warm else None
        r = dict(method=method, n_flights=n, warm_s=w, warm_min_s=min(warm) if warm else None,
                 warm_all_s=list(warm),
                 first_call_s=first,
                 compile_s=(None if first is None or w is None else max(first - w, 0.0)),
                 fits_per_s=(n / w if w else None), **kw)
        rows.append(r)
        log(f"  {method:<28} N={n:<4} warm {w:9.4f} s"
            + (f"  first {first:8.2f} s" if first is not None else ""))
        return r

    # ---- fwid.fit on single flights (N=1 row; the loop rows; the identity reference) ----
    log("fwid.fit (one flight per call)")
    _, first, warm, mem = time_calls(lambda: B.fwid_fit(0), args.fwid_repeats)
    th0, sd0, info0 = B.fwid_alone[0]
    row("fwid.fit", 1, warm, first, memory=dict(**mem, xla=B.fwid_fit_xla_memory(0)),
        fwid_info=info0, extrapolated=False)
    fwid_est[1] = (th0[None], sd0[None])
    n_loop = min(args.loop_flights, n_max)
    loop_t = [statistics.median(warm)]
    for i in range(1, n_loop):
        t0 = time.perf_counter()
        B.fwid_fit(i)
        loop_t.append(time.perf_counter() - t0)
    for n in sizes:
        if n == 1:
            continue
        k = min(n, n_loop)
        total = sum(loop_t[:k]) if k == n else statistics.mean(loop_t) * n
        row("fwid.fit loop", n, [total], None, extrapolated=k < n, measured_flights=k,
            fwid_info=[B.fwid_alone[i][2] for i in range(k)])

    # ---- fwid, N independent fits in one batched call ----
    log(f"fwid batched: {B.batched_label}" + ("" if B.use_fit_each else
        " (fwid.fit_each missing, or flights start from different values)"))
    for n in sizes:
        if n == 1 and args.quick:
            continue  # quick: N=1 is fwid.fit's row (saves one compilation)
        (theta, std, info), first, warm, mem = time_calls(B.fwid_batched(n),
                                                          args.fwid_batch_repeats)
        alone = [i for i in range(n) if i in B.fwid_alone]
        ident = None
        if alone:
            ta = np.stack([B.fwid_alone[i][0] for i in alone])
            ident = dict(flights_checked=len(alone),
                         max_rel_diff_all16=float(np.max(np.abs(theta[alone] - ta) / np.abs(ta))))
            ident["identical_1e-9"] = ident["max_rel_diff_all16"] <= 1e-9
        row(B.batched_label, n, warm, first,
            memory=dict(**mem, xla=B.fwid_batched_xla_memory(n)),
            identity_vs_fwid_fit_alone=ident, extrapolated=False, fwid_info=info)
        if n > 1 or 1 not in fwid_est:
            fwid_est[n] = (theta, std)

    # ---- JAX reference ----
    log("JAX reference (lax.scan RK4 + hand-written Gauss-Newton)")
    fit_one, fit_many = B._ref
    a1 = [x[0] if not isinstance(x, dict) else {k: v[0] for k, v in x.items()}
          for x in B.ref_args(1)]
    out, first, warm, mem = time_calls(lambda: _block(fit_one(*a1)), args.ref_repeats)
    r = row("JAX reference (jit)", 1, warm, first,
            memory=dict(**mem, xla=_xla_memory(fit_one.lower(*a1).compile())),
            ref_info=dict(iters=int(out["iters"]), halvings=int(out["halvings"]),
                          converged=bool(out["converged"])), extrapolated=False)
    r["agreement"] = _agreement(out["theta"][None], *fwid_est[1])
    for n in sizes:
        if n == 1 and args.quick:
            continue  # quick: N=1 is the jitted row
        a = B.ref_args(n)
        out, first, warm, mem = time_calls(lambda a=a: _block(fit_many(*a)), args.ref_repeats)
        r = row("JAX reference (vmap)", n, warm, first,
                memory=dict(**mem, xla=_xla_memory(fit_many.lower(*a).compile())),
                ref_info=dict(iters=out["iters"].tolist(), halvings=out["halvings"].tolist(),
                              all_converged=bool(out["converged"].all())), extrapolated=False)
        if n in fwid_est:
            r["agreement"] = _agreement(out["theta"], *fwid_est[n])

    # ---- scipy baseline (a Python loop over flights) ----
    log("scipy baseline (numpy RK4 + least_squares, finite differences)")
    n_sc = min(args.scipy_flights, n_max)
    sc_times, sc_theta, sc_info = [], [], []
    for i in range(n_sc):
        reps = args.scipy_repeats if i == 0 else 1
        ts = []
        for _ in range(reps):
            t0 = time.perf_counter()
            res = B.scipy_fit(i)
            ts.append(time.perf_counter() - t0)
        sc_times.append(statistics.median(ts))
        if i == 0:
            ts0 = ts
        sc_theta.append(res["theta"])
        sc_info.append(dict(relaxations=res["n_iter"], simulations=res["n_fev"],
                            converged=bool(res["converged"])))
        log(f"    flight {i}: {sc_times[-1]:.2f} s ({res['n_iter']} relaxations, "
            f"{res['n_fev']} simulations)")
    # tracemalloc slows Python down: a separate, untimed run (quick: the first relaxation
    # pass only, which allocates the same arrays as every later pass)
    tracemalloc.start()
    B.scipy_fit(0, max_outer=1 if args.quick else 50)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    sc_first_single = sc_times[0]
    scipy_time = {}
    for n in sizes:
        k = min(n, n_sc)
        if n == 1:
            total, warm_all = sc_first_single, ts0
        else:
            total = sum(sc_times[:k]) if k == n else statistics.mean(sc_times) * n
            warm_all = [total]
        r = row("scipy baseline", n, warm_all if n == 1 else [total], None,
                memory=dict(tracemalloc_peak_bytes=int(peak),
                            tracemalloc_scope="first relaxation pass" if args.quick
                            else "whole fit"),
                extrapolated=k < n, measured_flights=k, scipy_info=sc_info[:k])
        r["warm_s"] = total
        r["warm_min_s"] = min(ts0) * n if n == 1 else total
        r["fits_per_s"] = n / total
        scipy_time[n] = total
        if n in fwid_est:
            kk = min(k, n)
            r["agreement"] = _agreement(np.stack(sc_theta[:kk]), fwid_est[n][0][:kk],
                                        fwid_est[n][1][:kk])
            r["agreement"]["flights_compared"] = kk
    for r in rows:
        r["speedup_vs_scipy"] = scipy_time[r["n_flights"]] / r["warm_s"]
        if r["method"].startswith("fwid") and "agreement" not in r:
            r["agreement"] = dict(max_rel_diff_aero=0.0, max_diff_in_std_aero=0.0,
                                  note="the fwid reference itself")

    profile = (run_profile(B, args, rows[0]["warm_s"]) if args.profile else None)
    load1 = os.getloadavg()
    machine = dict(
        platform=platform.platform(), processor=platform.processor(),
        python=platform.python_version(), cpu_count=os.cpu_count(),
        cpus_usable=len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        loadavg_start=load0, loadavg_end=load1,
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
    problem = dict(
        model="fwid.longitudinal(): Eq. (7) + biases", free_parameters=list(NAMES),
        samples=N_SAMPLES, dt=DT, duration_s=N_SAMPLES * DT, inputs="elevator 3211 (even "
        "flights) / doublet (odd flights)", noise_std=dict(zip(("q", "u", "w", "theta"),
                                                             NOISE_STD)),
        true=dict(zip(NAMES, F["theta_true"].tolist())), constants=consts,
        constants_source=consts_source, start=args.start, seed=args.seed, sizes=sizes,
        fwid_fit_settings=B.fit_defaults,
        scipy_settings=dict(rtol=B.fit_defaults["cost_rtol"], method="trf", jac="2-point"),
        reference_settings=dict(max_iter=50, max_halvings=10, cost_rtol=1e-10, step_tol=1e-9),
    )
    return dict(machine=machine, problem=problem, rows=rows, profile=profile,
                quick=args.quick, repeats=dict(fwid=args.fwid_repeats,
                                               fwid_batched=args.fwid_batch_repeats,
                                               ref=args.ref_repeats,
                                               scipy_single=args.scipy_repeats),
                total_wall_s=time.perf_counter() - t_start)


def _version(mod):
    try:
        from importlib.metadata import version

        return version(mod)
    except Exception:
        return None


# --------------------------------------------------------------------------------------------
# Where fwid's time goes
# --------------------------------------------------------------------------------------------
def _times(fn, *a, repeats=15):
    """(median, min) wall time of warm calls: with other work on the machine the minimum is
    the steadier estimate of what the code itself costs."""
    jax.block_until_ready(fn(*a))
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*a))
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), min(ts)


def _aot(fn, *a):
    t0 = time.perf_counter()
    lowered = jax.jit(fn).lower(*a)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2 = time.perf_counter()
    return compiled, t1 - t0, t2 - t1


def run_profile(B, args, fit_warm_s):
    """Micro-benchmarks of fwid's parts against the scan, and what-ifs (runtime patches)."""
    import optimistix as optx

    print("profile: where fwid's time goes", flush=True)
    prof = {}
    exp = B.exps[0]
    sm, fb_args = B.fit_batch_args(0)
    theta0 = jnp.asarray(B.starts[0])
    c0 = {k: jnp.asarray(v) for k, v in B.F["consts_list"][0].items()}
    u0 = jnp.asarray(B.F["u"][0])
    x00 = jnp.asarray(B.F["x0"][0])

    def sim_diffrax(th):
        return fwid.simulate(sm, exp, sm.merge(th))[1]

    def sim_scan(th):
        return rk4_scan(lon_f_jax, th, x00, u0, DT, c0)

    parts = [("simulate, diffrax (fwid.simulate)", sim_diffrax),
             ("simulate, lax.scan RK4", sim_scan),
             ("jacfwd(simulate), diffrax ForwardMode", jax.jacfwd(sim_diffrax)),
             ("jacfwd(simulate), lax.scan RK4", jax.jacfwd(sim_scan))]
    if hasattr(_oe, "simulate_sensitivities"):  # what fwid's estimator runs per GN step
        parts.insert(3, ("outputs + sensitivities, diffrax (one solve)",
                         lambda th: _oe.simulate_sensitivities(sm, exp, sm.merge, th)))
    micro = {}
    for name, fn in parts:
        compiled, tl, tc = _aot(fn, theta0)
        med, mn = _times(compiled, theta0)
        micro[name] = dict(run_ms=1e3 * med, run_min_ms=1e3 * mn, trace_lower_s=tl,
                           compile_s=tc)
        print(f"  {name:<44} {1e3 * med:8.3f} ms (min {1e3 * mn:.3f})  trace+lower {tl:5.2f} s  "
              f"compile {tc:5.2f} s", flush=True)
    d = np.max(np.abs(np.asarray(sim_diffrax(theta0)) - np.asarray(sim_scan(theta0))))
    micro["max_abs_diff_diffrax_vs_scan"] = float(d)
    prof["micro"] = micro
    # The headline ratios, measured round-robin so that every method sees the same load.
    fit_one, fit_many = B._ref
    a1 = [x[0] if not isinstance(x, dict) else {k: v[0] for k, v in x.items()}
          for x in B.ref_args(1)]
    nb = min(4, len(B.starts))
    fbc, ar = B.fwid_batched(nb), B.ref_args(nb)
    calls = {"fwid.fit (N=1)": lambda: B.fwid_fit(0),
             "JAX reference jit (N=1)": lambda: _block(fit_one(*a1)),
             f"{B.batched_label} (N={nb})": fbc,
             f"JAX reference vmap (N={nb})": lambda: _block(fit_many(*ar))}
    for f in calls.values():  # compiled already unless --quick skipped a size
        f()
    times = {k: [] for k in calls}
    for _ in range(15):
        for k, f in calls.items():
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    il = {k: dict(median_s=statistics.median(v), min_s=min(v), all_s=v) for k, v in times.items()}
    names = list(calls)
    il["ratios"] = {
        "fwid.fit / reference (N=1)": dict(
            median=il[names[0]]["median_s"] / il[names[1]]["median_s"],
            min=il[names[0]]["min_s"] / il[names[1]]["min_s"]),
        f"{B.batched_label} / reference vmap (N={nb})": dict(
            median=il[names[2]]["median_s"] / il[names[3]]["median_s"],
            min=il[names[2]]["min_s"] / il[names[3]]["min_s"]),
        f"{B.batched_label} (N={nb}) / fwid.fit (N=1)": dict(
            median=il[names[2]]["median_s"] / il[names[0]]["median_s"],
            min=il[names[2]]["min_s"] / il[names[0]]["min_s"]),
        f"reference vmap (N={nb}) / reference jit (N=1)": dict(
            median=il[names[3]]["median_s"] / il[names[1]]["median_s"],
            min=il[names[3]]["min_s"] / il[names[1]]["min_s"]),
    }
    prof["interleaved"] = il
    for k in names:
        print(f"  interleaved {k:<28} median {il[k]['median_s']:.4f} s  min {il[k]['min_s']:.4f} s",
              flush=True)
    for k, v in il["ratios"].items():
        print(f"  ratio {k:<44} {v['median']:.2f}x median, {v['min']:.2f}x min", flush=True)
    info = B.fwid_alone[0][2]
    fmin = il[names[0]]["min_s"]
    prof["fwid_fit"] = dict(warm_s_table=fit_warm_s, warm_min_s_interleaved=fmin, **info,
                            ms_per_gauss_newton_step=1e3 * fmin / max(info["steps"], 1))
    ro = _block(fit_one(*a1))
    prof["reference"] = dict(iterations=int(ro["iters"]), halvings=int(ro["halvings"]),
                             ms_per_iteration=1e3 * il[names[1]]["min_s"] / int(ro["iters"]))

    kw = B.fit_defaults

    def build(label, **over):
        fn = functools.partial(_oe._fit_batch, sm, n_local_batch=0, **{**kw, **over})
        compiled, tl, tc = _aot(fn, *fb_args)
        out = _block(compiled(*fb_args))
        th = out["theta"] if "theta" in out else out["s"] * np.asarray(fb_args[1])
        r = dict(trace_lower_s=tl, compile_s=tc, passes=int(out["passes"]),
                 steps=int(out["steps"]),
                 max_rel_diff_vs_fwid_fit=float(np.max(np.abs(th / B.fwid_alone[0][0] - 1))))
        print(f"  what-if {label:<40} trace+lower {tl:5.2f} s compile {tc:5.2f} s  steps "
              f"{r['steps']:4d} (R relaxations {r['passes']})  "
              f"drel {r['max_rel_diff_vs_fwid_fit']:.1e}", flush=True)
        return compiled, r

    def scan_simulate(model, exp, params=None, *, x0=None):
        params = model.params if params is None else params
        x0 = exp.x0 if x0 is None else x0
        xs = rk4_scan(model.f, params, x0, exp.u, exp.t[1] - exp.t[0], exp.consts)
        return xs, xs

    def scan_sensitivities(model, exp, params_of, theta):
        def ys(th):
            return rk4_scan(model.f, params_of(th), exp.x0, exp.u, exp.t[1] - exp.t[0],
                            exp.consts)
        return ys(theta), jax.jacfwd(ys)(theta)

    variants = {}
    orig_sim = _oe.simulate
    orig_sens = getattr(_oe, "simulate_sensitivities", None)
    try:  # the patches matter while tracing only; the compiled programs keep what they saw
        variants["as is"] = build("as is")
        _oe.simulate = scan_simulate
        if orig_sens is not None:
            _oe.simulate_sensitivities = scan_sensitivities
        variants["lax.scan RK4 (jacfwd) instead of diffrax"] = build(
            "lax.scan RK4 (jacfwd) instead of diffrax")
    finally:
        _oe.simulate = orig_sim
        if orig_sens is not None:
            _oe.simulate_sensitivities = orig_sens
    # timed round-robin, with the hand-written reference as the yardstick
    wt = {k: [] for k in variants}
    wt["JAX reference (jit)"] = []
    for _ in range(15):
        for k, (compiled, _) in variants.items():
            t0 = time.perf_counter()
            _block(compiled(*fb_args))
            wt[k].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        _block(fit_one(*a1))
        wt["JAX reference (jit)"].append(time.perf_counter() - t0)
    ref_min, ref_med = min(wt["JAX reference (jit)"]), statistics.median(wt["JAX reference (jit)"])
    wi = {}
    for k, (_, r) in variants.items():
        r.update(warm_s=statistics.median(wt[k]), warm_min_s=min(wt[k]), all_s=wt[k],
                 vs_reference_median=statistics.median(wt[k]) / ref_med,
                 vs_reference_min=min(wt[k]) / ref_min)
        wi[k] = r
        print(f"  what-if {k:<52} warm {r['warm_s']:.3f} s (min {r['warm_min_s']:.3f}) = "
              f"{r['vs_reference_median']:.2f}x / {r['vs_reference_min']:.2f}x the reference "
              f"(median / min)", flush=True)
    wi["JAX reference (jit)"] = dict(warm_s=ref_med, warm_min_s=ref_min,
                                     all_s=wt["JAX reference (jit)"])
    prof["what_if"] = wi
    prof["note"] = ("what-ifs compile fwid's own _fit_batch (as fwid.fit calls it for one "
                    "flight) with names in fwid.estimate._output_error patched in this process "
                    "only (simulate / simulate_sensitivities -> a lax.scan RK4 with jacfwd); "
                    "fwid's files are unchanged")
    return prof


# --------------------------------------------------------------------------------------------
# Output
# --------------------------------------------------------------------------------------------
def _fmt_mem(r):
    m = r.get("memory") or {}
    if "tracemalloc_peak_bytes" in m:
        return f"{m['tracemalloc_peak_bytes'] / 2**20:.1f} MiB (tracemalloc)"
    parts = []
    if m.get("xla"):
        parts.append(f"{m['xla']['total'] / 2**20:.1f} MiB XLA")
    if "device_peak_growth_bytes" in m:
        parts.append(f"+{m['device_peak_growth_bytes'] / 2**20:.0f} MiB dev peak")
    if "rss_growth_mb" in m:
        parts.append(f"+{m['rss_growth_mb']:.0f} MiB RSS")
    return ", ".join(parts) if parts else "-"


def markdown(res):
    mc, pb = res["machine"], res["problem"]
    lines = [
        "# fwid speed benchmark",
        "",
        f"Machine: {mc['platform']}, {mc['cpu_count']} CPUs ({mc['cpus_usable']} usable), "
        f"JAX {mc['jax']} on **{mc['jax_backend']}** ({mc['device_kind']}); float64 "
        f"{'on' if mc['float64']['enabled'] else 'OFF'} (jax_enable_x64, "
        f"{'set by importing fwid' if mc['float64']['enabled_by_importing_fwid'] else 'set by speed.py'}); "
        f"load average {mc['loadavg_start'][0]:.1f} at start, {mc['loadavg_end'][0]:.1f} at end.",
        f"Problem: {pb['model']}, {len(pb['free_parameters'])} free parameters, "
        f"{pb['samples']} samples ({pb['duration_s']:.1f} s at {1 / pb['dt']:.0f} Hz), "
        f"{pb['inputs']}, white noise; start: {pb['start']}. "
        f"{'Quick run. ' if res['quick'] else ''}Total {res['total_wall_s']:.0f} s.",
        "",
        "| method | N | warm median (min) [s] | compile [s] | fits/s | speed-up vs scipy | peak memory "
        "| aero max rel diff vs fwid (in CR std) | note |",
        "|---|---:|---:|---:|---:|---:|---|---|---|",
    ]
    for r in res["rows"]:
        ag = r.get("agreement") or {}
        agree = ("-" if not ag else "ref" if ag.get("note") else
                 f"{ag['max_rel_diff_aero']:.1e} ({ag['max_diff_in_std_aero']:.1e})")
        note = []
        if r.get("extrapolated"):
            note.append(f"**extrapolated** from {r['measured_flights']} measured flight(s)")
        elif r.get("measured_flights") is not None and r["method"] != "scipy baseline":
            note.append(f"{r['measured_flights']} flights measured")
        idt = r.get("identity_vs_fwid_fit_alone")
        if idt:
            note.append(f"vs fwid.fit alone ({idt['flights_checked']} flights): "
                        f"{idt['max_rel_diff_all16']:.1e} "
                        f"{'identical' if idt['identical_1e-9'] else '**NOT identical**'}")
        if r.get("fwid_info") and isinstance(r["fwid_info"], dict):
            fi = r["fwid_info"]
            if "steps" in fi and isinstance(fi["steps"], int):
                note.append(f"{fi['steps']} GN steps ({fi['passes']} R relaxations)")
            elif "steps" in fi:
                note.append(f"GN steps {min(fi['steps'])}-{max(fi['steps'])}")
        if r.get("ref_info"):
            it = r["ref_info"]["iters"]
            note.append(f"{it if isinstance(it, int) else f'{min(it)}-{max(it)}'} iterations")
        comp = "-" if r["compile_s"] is None else f"{r['compile_s']:.1f}"
        lines.append(
            f"| {r['method']} | {r['n_flights']} | {r['warm_s']:.3f} ({r['warm_min_s']:.3f}) | "
            f"{comp} | "
            f"{r['fits_per_s']:.3g} | {r['speedup_vs_scipy']:.3g} | {_fmt_mem(r)} | {agree} | "
            f"{'; '.join(note)} |")
    lines += [
        "",
        "warm: median of repeated calls after the first; compile: first call minus warm. "
        "fwid for N > 1: `fwid.fit_each` (one vmapped call), or `jax.vmap` over fwid's internal "
        "`_fit_batch` where fwid has no `fit_each`. Memory: XLA = temporaries + arguments + outputs of the compiled program; "
        "RSS = growth of the process's peak resident set during the calls (0 when an earlier "
        "step already reached it); scipy: tracemalloc peak of Python allocations.",
    ]
    rw = {(r["method"], r["n_flights"]): r for r in res["rows"]}
    f1, j1 = rw.get(("fwid.fit", 1)), rw.get(("JAX reference (jit)", 1))
    if f1 and j1:
        lines += ["", f"Issue 4 targets: fwid.fit warm / hand-written JAX warm = "
                  f"{f1['warm_s'] / j1['warm_s']:.2f}x median, "
                  f"{f1['warm_min_s'] / j1['warm_min_s']:.2f}x min (target <= 2x); fwid.fit "
                  f"warm speed-up over scipy {f1['speedup_vs_scipy']:.0f}x (target >= 50x); "
                  f"fwid.fit compile {f1['compile_s']:.1f} s (target < 30 s)."]
    lines += ["", "Batch scaling, warm time for N flights / warm time for 1 flight (fwid: the "
              "batched call over fwid.fit on one flight):", ""]
    by = {(r["method"], r["n_flights"]): r["warm_s"] for r in res["rows"]}
    batched = next((r["method"] for r in res["rows"]
                    if r["method"] in ("fwid.fit_each", "fwid vmap(_fit_batch)")), None)
    for name, one, many in [("fwid", ("fwid.fit", 1), batched),
                            ("fwid.fit loop", ("fwid.fit", 1), "fwid.fit loop"),
                            ("JAX reference", ("JAX reference (jit)", 1), "JAX reference (vmap)"),
                            ("scipy", ("scipy baseline", 1), "scipy baseline")]:
        parts = [f"N={n}: {by[(many, n)] / by[one]:.2f}x" for n in res["problem"]["sizes"]
                 if n > 1 and (many, n) in by and one in by]
        if parts:
            lines.append(f"- {name}: " + ", ".join(parts))
    prof = res.get("profile")
    if prof:
        lines += ["", "## Profile (one flight)", "", "| part | run median (min) [ms] | "
                  "trace+lower [s] | compile [s] |", "|---|---:|---:|---:|"]
        for k, v in prof["micro"].items():
            if isinstance(v, dict):
                lines.append(f"| {k} | {v['run_ms']:.3f} ({v['run_min_ms']:.3f}) | "
                             f"{v['trace_lower_s']:.2f} | {v['compile_s']:.2f} |")
        il = prof["interleaved"]
        lines += ["", "Interleaved timings (15 rounds, round-robin, so all see the same load):", "",
                  "| call | median [s] | min [s] |", "|---|---:|---:|"]
        for k, v in il.items():
            if k != "ratios":
                lines.append(f"| {k} | {v['median_s']:.4f} | {v['min_s']:.4f} |")
        lines += [""] + [f"- {k}: {v['median']:.2f}x (median), {v['min']:.2f}x (min)"
                         for k, v in il["ratios"].items()]
        ff = prof["fwid_fit"]
        rf = prof["reference"]
        lines += ["", f"fwid.fit on flight 0: {ff['passes']} R relaxations, {ff['steps']} "
                  f"Gauss-Newton steps, {ff['ms_per_gauss_newton_step']:.1f} ms per step (from "
                  f"the minimum time). JAX reference: {rf['iterations']} iterations "
                  f"({rf['halvings']} halvings), {rf['ms_per_iteration']:.1f} ms per iteration.",
                  "",
                  "What-ifs (" + prof["note"] + "):", "",
                  "| variant | warm median (min) [s] | x reference (median / min) | "
                  "trace+lower [s] | compile [s] | GN steps | R relaxations | "
                  "rel diff vs fwid.fit |", "|---|---:|---:|---:|---:|---:|---|---:|"]
        for k, v in prof["what_if"].items():
            if "steps" not in v:
                lines.append(f"| {k} | {v['warm_s']:.4f} ({v['warm_min_s']:.4f}) | 1 | | | | | |")
                continue
            pp = v.get("passes", "")
            lines.append(f"| {k} | {v['warm_s']:.3f} ({v['warm_min_s']:.3f}) | "
                         f"{v['vs_reference_median']:.2f} / {v['vs_reference_min']:.2f} | "
                         f"{v['trace_lower_s']:.2f} | {v['compile_s']:.2f} | {v['steps']} | {pp} | "
                         f"{v['max_rel_diff_vs_fwid_fit']:.1e} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "results" / "speed.json"))
    ap.add_argument("--sizes", default="1,4,16,64,256", help="numbers of flights")
    ap.add_argument("--quick", action="store_true",
                    help="sizes 1,4, fewer repeats, one scipy fit (< 3 min on 2 CPU cores)")
    ap.add_argument("--profile", action="store_true", help="also profile fwid's parts")
    ap.add_argument("--start", choices=("true1.2", "least-squares"), default="true1.2",
                    help="start values: true x 1.2, or fwid's least-squares start per flight")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=3, help="warm repeats (>= 3)")
    ap.add_argument("--scipy-flights", type=int, default=4,
                    help="flights the scipy loop is timed on (more are extrapolated)")
    ap.add_argument("--loop-flights", type=int, default=4,
                    help="flights fitted one by one with fwid.fit (identity check, loop rows)")
    args = ap.parse_args(argv)
    if args.quick:
        args.sizes = "1,4"
        args.fwid_repeats, args.fwid_batch_repeats, args.ref_repeats = 3, 1, 7
        args.scipy_repeats = 1
        args.scipy_flights = min(args.scipy_flights, 1)
    else:
        args.fwid_repeats = args.fwid_batch_repeats = args.repeats
        args.ref_repeats = max(args.repeats, 5)
        args.scipy_repeats = args.repeats
    res = run(args)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=1, default=_jsonable) + "\n")
    md = markdown(res)
    out.with_suffix(".md").write_text(md)
    print()
    print(md)
    print(f"wrote {out} and {out.with_suffix('.md')}")


def _jsonable(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


if __name__ == "__main__":
    main()
