"""Benchmark: where `fwid.fit_each`'s time goes, stage by stage, beside the hand-written
layouts of the kernel, and the parallel-in-time simulation against the sequential one.

    python benchmarks/stages.py [--sizes 1,64] [--rounds 10]
                                [--out benchmarks/results/speed_stages.json]

(`python benchmarks/speed.py --stages [SIZES]` runs the same.) The problem is `speed.py`'s
(`cases/delfly_speed.py`: Eq. 7 + biases, 16 parameters, 900 samples, start true x 1.2).

1. **fit_each by stage**, per size: the whole call (minimum of `--repeats`), split by timing
   fwid's own functions in this process (wrapped, not changed): the checks and starts
   (`prepare`), the batched estimator call, the results (`_result`, the stability check);
   and, inside the batched call, the kernels of one Gauss-Newton iteration on the same
   flights, each compiled alone on one device and timed round-robin: the outputs and their
   16 sensitivities (fwid's `vmap`, flights outermost; the hand-written scan under `vmap`;
   the hand-written scan with the flights innermost), one trial simulation, the normal
   equations, the Newton solve, the R relaxation (Eq. 11). Iterations x their sum against
   the batched call gives what the solver's loop adds (its bookkeeping and the `vmap`'s
   selects over the whole loop state).
2. **Parallel in time** (`fwid.simulate(..., time_parallel=True)`): the outputs and their
   sensitivities of one flight of 900 and 9000 samples by the associative scan and by the
   sequential scan, their time and their largest relative difference.

On a GPU (`jax.default_backend() == "gpu"`) everything JAX runs there; on a CPU the GPU
section says so. Writes `--out` (JSON) and the same name with `.md`.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import fwid  # noqa: E402
from fwid.estimate import _each  # noqa: E402
from fwid.estimate._gauss_newton import NoiseModel, _scaled_newton  # noqa: E402
from fwid.simulation._simulate import simulate, simulate_sensitivities  # noqa: E402

import _shared as M  # noqa: E402
import cases.delfly_speed as P  # noqa: E402
from simd import sensitivities_hand, sensitivities_inner  # noqa: E402


class _Timer:
    """Wraps module attributes so that each call's wall time adds to a named total."""

    def __init__(self):
        self.totals, self._saved = {}, []

    def wrap(self, module, name, label):
        fn = getattr(module, name)

        def timed(*a, **k):
            t0 = time.perf_counter()
            out = fn(*a, **k)
            out = jax.block_until_ready(out) if label == "batched call" else out
            self.totals[label] = self.totals.get(label, 0.0) + time.perf_counter() - t0
            return out
        self._saved.append((module, name, fn))
        setattr(module, name, timed)

    def restore(self):
        for module, name, fn in reversed(self._saved):
            setattr(module, name, fn)


def fit_each_stages(model, exps, start, repeats):
    """The whole `fit_each` call and its Python-level stages (the minimum over `repeats`
    warm calls of each)."""
    call = lambda: fwid.fit_each(model, exps, start=start)  # noqa: E731
    res = call()
    best = None
    for _ in range(repeats):
        tm = _Timer()
        tm.wrap(_each, "prepare", "checks and starts")
        tm.wrap(_each, "_run_batched", "batched call")
        tm.wrap(_each, "_result", "results")
        tm.wrap(_each, "with_instability", "results")
        try:
            t0 = time.perf_counter()
            res = call()
            total = time.perf_counter() - t0
        finally:
            tm.restore()
        stages = dict(tm.totals, total=total)
        best = stages if best is None or total < best["total"] else best
    best["other"] = best["total"] - sum(v for k, v in best.items() if k != "total")
    steps = [int(r.steps) for r in res]
    return best, steps


def kernels(model, F, n, rounds):
    """One Gauss-Newton iteration's kernels for `n` flights on one device, timed round-robin."""
    dev = jax.devices()[0]
    put = lambda a: jax.device_put(a, dev)  # noqa: E731
    exps = [P.experiment(F, i) for i in range(n)]
    batch = put(fwid.stack_experiments(exps))
    th = put(jnp.asarray(np.tile(1.2 * F["theta_true"], (n, 1))))
    sm = model.with_params(dict(zip(P.NAMES, map(float, th[0]))))
    u_n = put(jnp.asarray(np.stack(F["u"][:n])))
    x0_n = put(jnp.asarray(np.stack(F["x0"][:n])))
    c_n = {k: put(jnp.asarray([c[k] for c in F["consts_list"][:n]])) for k in P.CONST_KEYS}
    dt = P.DT

    def flights(fn):  # fit_each maps over the flights, except for one flight alone
        if n > 1:
            return jax.jit(jax.vmap(fn))
        return jax.jit(lambda t_, e: jax.tree.map(
            lambda a: a[None], fn(t_[0], jax.tree.map(lambda a: a[0], e))))

    sens = flights(lambda t_, e: simulate_sensitivities(sm, e, sm.merge, t_, paired=n > 1))
    sim = flights(lambda t_, e: simulate(sm, e, sm.merge(t_))[1])

    ref = jax.jit(jax.vmap(lambda t_, x0, u, c: sensitivities_hand(t_, x0, u, c, dt)))
    inner = jax.jit(lambda t_, x0, u, c: sensitivities_inner(t_, x0, u, c, dt))
    ys, S = sens(th, batch)
    v = batch.z - ys
    J = -S
    noise = jax.vmap(lambda z, m: NoiseModel.of_data(z, m, False))(batch.z, batch.mask)
    normal = jax.jit(jax.vmap(lambda nm, v_, J_: nm.gradient_terms(v_, J_)))
    H, g = normal(noise, v, J)
    free = jnp.ones(th.shape[1], bool)
    solve = jax.jit(jax.vmap(lambda H_, g_: _scaled_newton(H_, g_, free)))
    relax = jax.jit(jax.vmap(lambda nm, v_: nm.R(v_)))
    a_i = (th.T, x0_n.T, jnp.transpose(u_n, (1, 2, 0)), c_n)
    calls = {
        "sensitivities, fwid (vmap: flights outermost)": lambda: sens(th, batch),
        "sensitivities, hand-written scan, vmap": lambda: ref(th, x0_n, u_n, c_n),
        "sensitivities, hand-written scan, flights innermost": lambda: inner(*a_i),
        "trial simulation (outputs only)": lambda: sim(th, batch),
        "normal equations": lambda: normal(noise, v, J),
        "Newton solve": lambda: solve(H, g),
        "R relaxation (Eq. 11)": lambda: relax(noise, v),
    }
    out = M.interleaved({k: (lambda f=f: jax.block_until_ready(f())) for k, f in calls.items()},
                        rounds)
    steps = P.N_SAMPLES - 1
    for r in out.values():
        r["ns_per_flight_step"] = 1e9 * r["min_s"] / (n * steps)
        del r["all_s"]
    return out


def parallel_time(model, F, samples, rounds):
    """The outputs and sensitivities of flight 0 stretched to `samples` samples (its input
    repeated), by the associative scan and the sequential scan."""
    e = P.experiment(F, 0)
    reps = -(-samples // e.n)
    t = np.arange(samples) * P.DT
    u = np.tile(np.asarray(e.u), (reps, 1))[:samples]
    exp = fwid.Experiment(t, u, np.zeros((samples, 4)), np.asarray(e.x0), e.consts)
    th = jnp.asarray(1.2 * F["theta_true"])
    sm = model.with_params(dict(zip(P.NAMES, map(float, th))))
    out, fns = {}, {}
    for par in (False, True):
        fn = jax.jit(lambda t_, ex, par=par: simulate_sensitivities(sm, ex, sm.merge, t_,
                                                                    time_parallel=par))
        t0 = time.perf_counter()
        out[par] = jax.block_until_ready(fn(th, exp))
        fns["parallel" if par else "sequential"] = (fn, time.perf_counter() - t0)
    tm = M.interleaved({k: (lambda f=f: jax.block_until_ready(f(th, exp)))
                        for k, (f, _) in fns.items()}, rounds)
    (ys, S), (yp, Sp) = out[False], out[True]
    scale = jnp.max(jnp.abs(S), axis=(0, 1))
    return dict(
        samples=samples,
        outputs_rel=float(jnp.max(jnp.abs(yp - ys)) / jnp.max(jnp.abs(ys))),
        sensitivities_rel=float(jnp.max(jnp.abs(Sp - S) / scale)),
        **{k: dict(min_s=tm[k]["min_s"], median_s=tm[k]["median_s"],
                   first_call_s=fns[k][1]) for k in fns})


def run(args) -> dict:
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    sizes = [int(s) for s in args.sizes.split(",")]
    consts, _ = P.vehicle_constants()
    F = P.make_flights(max(sizes), 0, consts)
    exps = [P.experiment(F, i) for i in range(max(sizes))]
    model = fwid.longitudinal()
    start = model.with_params(dict(zip(P.NAMES, map(float, 1.2 * F["theta_true"]))))
    res = dict(sizes={}, backend=jax.default_backend(),
               device=str(jax.devices()[0].device_kind), devices=jax.device_count())
    for n in sizes:
        print(f"fit_each by stage: {n} flights", flush=True)
        stages, steps = fit_each_stages(model, exps[:n], start, args.repeats)
        ks = kernels(model, F, n, args.rounds)
        # every iteration evaluates its trial point with its sensitivities (the Jacobian is
        # computed once per point): the outputs-only simulation is not part of it
        per_iter = sum(v["min_s"] for k, v in ks.items()
                       if (not k.startswith("sensitivities,") or "fwid" in k)
                       and not k.startswith("trial"))
        res["sizes"][n] = dict(stages=stages, gn_steps=steps, kernels=ks,
                               kernel_per_iteration_s=per_iter)
    res["parallel_time"] = []
    for s in (900, 9000):
        print(f"parallel in time: {s} samples", flush=True)
        res["parallel_time"].append(parallel_time(model, F, s, args.rounds))
    res["machine"] = M.machine(load0)
    res["total_s"] = time.perf_counter() - t_start
    return res


def markdown(res) -> str:
    lines = ["# fit_each by stage, and parallel in time (`benchmarks/stages.py`)", "",
             M.machine_line(res["machine"], "stages.py"), "",
             f"Problem: `cases/delfly_speed.py` (Eq. 7 + biases, 16 parameters, 900 samples), "
             f"start true x 1.2; {res['devices']} device(s), backend **{res['backend']}** "
             f"({res['device']}). Total {res['total_s']:.0f} s.", ""]
    for n, r in sorted(res["sizes"].items(), key=lambda kv: int(kv[0])):
        st = r["stages"]
        iters = max(r["gn_steps"])
        lines += [f"## {n} flight(s): `fit_each` {st['total']:.3f} s, Gauss-Newton steps "
                  f"{min(r['gn_steps'])}-{iters} per flight", "",
                  "| stage | time [s] | share |", "|---|---:|---:|",
                  *[f"| {k} | {v:.4f} | {100 * v / st['total']:.0f} % |"
                    for k, v in st.items() if k != "total"], "",
                  f"Inside the batched call, one iteration's kernels on one device "
                  f"({n} flights, minimum of the round-robin):", "",
                  "| kernel | min [ms] | median [ms] | ns per flight-step |",
                  "|---|---:|---:|---:|",
                  *[f"| {k} | {1e3 * v['min_s']:.2f} | {1e3 * v['median_s']:.2f} | "
                    f"{v['ns_per_flight_step']:.0f} |" for k, v in r["kernels"].items()], "",
                  f"One iteration (fwid's sensitivities at the trial point + normal equations "
                  f"+ solve + R; the outputs-only simulation is not run by the solver): "
                  f"{1e3 * r['kernel_per_iteration_s']:.2f} ms; x {iters} "
                  f"iterations (the slowest flight's steps, which the `vmap` runs for all) = "
                  f"{iters * r['kernel_per_iteration_s']:.3f} s of the batched call's "
                  f"{st.get('batched call', float('nan')):.3f} s (on "
                  f"{res['devices']} device(s); the kernels on one).", ""]
    lines += ["## Parallel in time (one flight, outputs + 16 sensitivities)", "",
              "| samples | sequential min [ms] | parallel min [ms] | parallel first call [s] | "
              "outputs rel. diff | sensitivities rel. diff |",
              "|---:|---:|---:|---:|---:|---:|",
              *[f"| {p['samples']} | {1e3 * p['sequential']['min_s']:.2f} | "
                f"{1e3 * p['parallel']['min_s']:.2f} | {p['parallel']['first_call_s']:.1f} | "
                f"{p['outputs_rel']:.1e} | {p['sensitivities_rel']:.1e} |"
                for p in res["parallel_time"]], "",
              "## GPU", ""]
    lines.append("Measured on the GPU above." if res["backend"] == "gpu"
                 else "No GPU on this machine: the rows above are the CPU's. On a GPU the same "
                 "command measures there (`jax.default_backend()`).")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1,64")
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "speed_stages.json"))
    M.run_and_write(run, markdown, ap.parse_args(argv))


if __name__ == "__main__":
    main()
