"""Benchmark: many flights against the machine's limit. Where does a batched fit's time go,
would laying the flights innermost (the SIMD lanes) help, and how far is it from the
arithmetic of the problem?

    python benchmarks/simd.py [--flights 64] [--rounds 30]
                              [--out benchmarks/results/simd.json]

The problem is `speed.py`'s (`cases/delfly_speed.py`: Eq. 7 + biases, 16 parameters, 900 samples,
start true x 1.2). Measured in one run:

1. **The kernel of a Gauss-Newton step** (the outputs and their 16 sensitivities over a
   flight: 899 RK4 steps of a 4 + 16 x 4 state) for `--flights` flights on one CPU device,
   in three layouts, timed round-robin (minimum and median of `--rounds`):
   - fwid: `simulate_sensitivities` under `jax.vmap` over the flights (what `fit_each` runs:
     flights outermost, the state `(N, 4)` and its sensitivities `(N, 16, 4)`);
   - hand-written `lax.scan` RK4 with `jacfwd`, under `jax.vmap` (the same layout);
   - hand-written `lax.scan` RK4 written on `(17, 4, N)` arrays, **flights innermost**: every
     operation of the model acts on a vector of N flights, the layout SIMD units want.
   All three compute the same numbers (checked).
2. **The arithmetic**: floating-point operations of one RK4 step of the kernel and of the
   normal equations (`sum J^T R^-1 J`, `J^T R^-1 v`) per flight, from XLA's cost analysis of
   the flights-innermost programs (one step, not the loop: XLA counts a loop body once).
3. **The machine's limit**: the rate of a float64 matrix product (1024 x 1024; XLA runs it
   on every core), the most the machine gives floating-point code, and one core's share of
   it; the kernels' rates in the same units.
4. **`fwid.fit_each`** on the N flights (the default devices: both cores) and on one: its
   Gauss-Newton steps, and the arithmetic rate those steps imply.

Writes `--out` (JSON) and the same name with `.md`.
"""

from __future__ import annotations

import argparse
import os
import statistics
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
from fwid.simulation._simulate import simulate_sensitivities  # noqa: E402

import _shared as M  # noqa: E402
import cases.delfly_speed as P  # noqa: E402
from peers.jax_output_error import rk4_scan  # noqa: E402


def _flops(fn, *a) -> float:
    """XLA's count of the floating-point operations of `jit(fn)(*a)`."""
    ca = jax.jit(fn).lower(*a).compile().cost_analysis()
    ca = ca[0] if isinstance(ca, (list, tuple)) else ca
    return float(ca.get("flops", float("nan")))


def inner_field(c):
    """The state and its 16 sensitivities' derivative, flights innermost: `y` `(17, 4, N)`,
    `th` `(16, N)`, `uk` `(1, N)`, every constant `(N,)`."""
    def f_aug(y, uk, th):
        basis = jnp.eye(16, dtype=th.dtype)[:, :, None] * jnp.ones_like(th[0])  # (16, 16, N)
        fx, dS = jax.vmap(
            lambda s, e: jax.jvp(lambda x, t_: P.lon_f_jax(x, uk, t_, c), (y[0], th), (s, e)),
            out_axes=(None, 0))(y[1:], basis)
        return jnp.concatenate([fx[None], dS], axis=0)
    return f_aug


def rk4_step(f_aug, th, dt):
    def step(y, inp):
        u1, uh, u2 = inp
        k1 = f_aug(y, u1, th)
        k2 = f_aug(y + 0.5 * dt * k1, uh, th)
        k3 = f_aug(y + 0.5 * dt * k2, uh, th)
        k4 = f_aug(y + dt * k3, u2, th)
        y1 = y + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
        return y1, y1
    return step


def sensitivities_inner(th, x0, u, c, dt):
    """Outputs and sensitivities of N flights, flights innermost: `th` `(16, N)`, `x0`
    `(4, N)`, `u` `(n, 1, N)` -> `(n, 17, 4, N)` (row 0 the states)."""
    y0 = jnp.concatenate([x0[None], jnp.zeros((16,) + x0.shape, x0.dtype)], axis=0)
    um = 0.5 * (u[:-1] + u[1:])
    _, ys = jax.lax.scan(rk4_step(inner_field(c), th, dt), y0, (u[:-1], um, u[1:]))
    return jnp.concatenate([y0[None], ys], axis=0)


def sensitivities_hand(th, x0, u, c, dt):
    """Outputs and sensitivities of one flight by the hand-written `lax.scan` RK4 and
    `jax.jacfwd` (vmap it for the flights-outermost layout): `(n, 4)`, `(n, 4, 16)`."""
    def sim(t_):
        y = rk4_scan(P.lon_f_jax, t_, x0, u, dt, c)
        return y, y
    S, y = jax.jacfwd(sim, has_aux=True)(th)
    return y, S


def normal_equations_inner(v, S):
    """`sum_k S_k^T R^-1 S_k` and `S_k^T R^-1 v_k` for N flights, flights innermost: `v`
    `(n, 4, N)`, `S` `(n, 16, 4, N)`; R of Eq. (11) per flight."""
    R = jnp.einsum("kiN,kjN->Nij", v, v) / v.shape[0]
    Ri = jnp.linalg.inv(R)
    H = jnp.einsum("kpiN,Nij,kqjN->Npq", S, Ri, S)
    g = jnp.einsum("kpiN,Nij,kjN->Np", S, Ri, v)
    return H, g


def run(args) -> dict:
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    n = args.flights
    consts, _ = P.vehicle_constants()
    F = P.make_flights(n, 0, consts)
    exps = [P.experiment(F, i) for i in range(n)]
    model = fwid.longitudinal()
    thetas = jnp.asarray(np.tile(1.2 * F["theta_true"], (n, 1)))  # (N, 16)
    dt = P.DT
    cdev = jax.devices("cpu")[0]
    put = lambda a: jax.device_put(a, cdev)  # noqa: E731

    # --- the kernels, one device ----------------------------------------------------------
    batch = put(fwid.stack_experiments(exps))
    sm = model.with_params(dict(zip(P.NAMES, map(float, thetas[0]))))
    th_n = put(thetas)
    u_n = put(jnp.asarray(np.stack(F["u"])))  # (N, n, 1)
    x0_n = put(jnp.asarray(np.stack(F["x0"])))
    c_n = {k: put(jnp.asarray([c[k] for c in F["consts_list"]])) for k in P.CONST_KEYS}

    fwid_kernel = jax.jit(jax.vmap(  # as fit_each runs it (paired: its layout for many flights)
        lambda th, e: simulate_sensitivities(sm, e, sm.merge, th, paired=True)))

    ref_kernel = jax.jit(jax.vmap(lambda th, x0, u, c: sensitivities_hand(th, x0, u, c, dt)))
    inner_kernel = jax.jit(lambda th, x0, u, c: sensitivities_inner(th, x0, u, c, dt))
    th_i, x0_i, u_i = th_n.T, x0_n.T, jnp.transpose(u_n, (1, 2, 0))  # flights last

    y_f, S_f = fwid_kernel(th_n, batch)
    y_r, S_r = ref_kernel(th_n, x0_n, u_n, c_n)
    Y_i = inner_kernel(th_i, x0_i, u_i, c_n)
    y_i, S_i = jnp.moveaxis(Y_i[:, 0], -1, 0), jnp.moveaxis(Y_i[:, 1:], -1, 0)  # (N,n,4),(N,n,16,4)
    agree = dict(
        fwid_vs_inner=float(jnp.max(jnp.abs(S_f - jnp.swapaxes(S_i, 2, 3)))
                            / jnp.max(jnp.abs(S_f))),
        ref_vs_inner=float(jnp.max(jnp.abs(S_r - jnp.swapaxes(S_i, 2, 3)))
                           / jnp.max(jnp.abs(S_r))),
        outputs=float(max(jnp.max(jnp.abs(y_f - y_i)), jnp.max(jnp.abs(y_r - y_i)))))
    calls = {
        "fwid (vmap: flights outermost)": lambda: jax.block_until_ready(
            fwid_kernel(th_n, batch)),
        "hand-written scan, vmap (flights outermost)": lambda: jax.block_until_ready(
            ref_kernel(th_n, x0_n, u_n, c_n)),
        "hand-written scan, flights innermost": lambda: jax.block_until_ready(
            inner_kernel(th_i, x0_i, u_i, c_n)),
    }
    print(f"kernels: {n} flights, {args.rounds} rounds round-robin", flush=True)
    kernels = M.interleaved(calls, args.rounds)

    # --- the arithmetic --------------------------------------------------------------------
    steps = P.N_SAMPLES - 1
    y1 = jnp.concatenate([x0_i[None], jnp.zeros((16,) + x0_i.shape)], axis=0)
    one_step = rk4_step(inner_field(c_n), th_i, dt)
    flops_step = _flops(lambda y, a, b, c: one_step(y, (a, b, c))[0], y1, u_i[0], u_i[0],
                        u_i[1]) / n
    v_i = jnp.transpose(jnp.asarray(np.stack(F["z"])), (1, 2, 0)) - Y_i[:, 0]
    flops_normal = _flops(normal_equations_inner, v_i, Y_i[:, 1:]) / n
    # one Gauss-Newton step: the sensitivities, the normal equations and one trial simulation
    # of the outputs alone (about 1/17 of the sensitivities' work)
    flops_sim_step = _flops(
        lambda y, a, b, c: rk4_step(lambda yy, uk, th: P.lon_f_jax(yy, uk, th, c_n), th_i,
                                    dt)(y, (a, b, c))[0], x0_i, u_i[0], u_i[0], u_i[1]) / n
    flops_gn = steps * (flops_step + flops_sim_step) + flops_normal
    arithmetic = dict(flops_per_rk4_step_with_sensitivities=flops_step,
                      flops_per_rk4_step_outputs_only=flops_sim_step,
                      flops_normal_equations=flops_normal,
                      flops_per_gauss_newton_step=flops_gn,
                      flops_kernel=steps * flops_step)

    # --- the machine's limit ---------------------------------------------------------------
    devs = jax.devices("cpu")
    a = jax.random.normal(jax.random.key(0), (1024, 1024), dtype=jnp.float64)
    mm = jax.jit(lambda x: x @ x)
    a = put(a)
    pk = M.interleaved({"mm": lambda: jax.block_until_ready(mm(a))}, 10)["mm"]
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    # XLA's CPU matrix product runs on every core (its own thread pool), even on one device
    peak = dict(matmul_min_s=pk["min_s"], gflops=2.0 * 1024 ** 3 / pk["min_s"] / 1e9,
                cores=cores)
    peak["gflops_per_core"] = peak["gflops"] / cores
    for k, v in kernels.items():
        v["gflops"] = n * steps * flops_step / v["min_s"] / 1e9
        v["ns_per_flight_step"] = 1e9 * v["min_s"] / (n * steps)

    # --- fwid.fit_each (default devices) ---------------------------------------------------
    print("fwid.fit_each", flush=True)
    start = model.with_params(dict(zip(P.NAMES, map(float, thetas[0]))))
    fe = {}
    for k in sorted({1, n}):
        call = lambda k=k: fwid.fit_each(model, exps[:k], start=start)  # noqa: E731
        res = call()
        ts = []
        for _ in range(args.fit_repeats):
            t0 = time.perf_counter()
            res = call()
            ts.append(time.perf_counter() - t0)
        gn = [int(r.steps) for r in res]
        tot = sum(gn)
        fe[k] = dict(min_s=min(ts), median_s=statistics.median(ts), gn_steps=gn,
                     gn_steps_total=tot,
                     gflops=tot * flops_gn / min(ts) / 1e9)
    return dict(machine=M.machine(load0), flights=n, samples=P.N_SAMPLES, rounds=args.rounds,
                agreement=agree, kernels=kernels, arithmetic=arithmetic, peak=peak,
                fit_each=fe, devices=len(devs), total_s=time.perf_counter() - t_start)


def markdown(res) -> str:
    n = res["flights"]
    ar = res["arithmetic"]
    pk, pk1 = res["peak"]["gflops"], res["peak"]["gflops_per_core"]
    lines = [
        "# Many flights against the machine's limit (`benchmarks/simd.py`)", "",
        M.machine_line(res["machine"], "simd.py"), "",
        f"Problem: `cases/delfly_speed.py` (Eq. 7 + biases, 16 parameters, {res['samples']} samples), "
        f"{n} flights. Total {res['total_s']:.0f} s.", "",
        "## The arithmetic (XLA's cost analysis, per flight)", "",
        f"- one RK4 step of the outputs and their 16 sensitivities: "
        f"{ar['flops_per_rk4_step_with_sensitivities']:.0f} flops; of the outputs alone "
        f"{ar['flops_per_rk4_step_outputs_only']:.0f}",
        f"- the normal equations: {ar['flops_normal_equations'] / 1e6:.2f} Mflop",
        f"- one Gauss-Newton step (sensitivities + normal equations + one trial simulation): "
        f"{ar['flops_per_gauss_newton_step'] / 1e6:.2f} Mflop", "",
        "## The machine's limit", "",
        f"A float64 1024 x 1024 matrix product (XLA runs it on all {res['peak']['cores']} cores): "
        f"{1e3 * res['peak']['matmul_min_s']:.1f} ms, **{pk:.1f} GFLOP/s**, {pk1:.1f} per core. "
        "A solver's loop runs on one core (its steps depend on one another), so one core's "
        "share is the limit of one device's kernel below, the whole for `fit_each` on all "
        "devices.", "",
        f"## The kernel of a Gauss-Newton step, {n} flights, one device "
        f"({res['rounds']} rounds round-robin)", "",
        "| layout | min [ms] | median [ms] | ns per flight-step | GFLOP/s | of one core's "
        "share |", "|---|---:|---:|---:|---:|---:|",
        *[f"| {k} | {1e3 * v['min_s']:.1f} | {1e3 * v['median_s']:.1f} | "
          f"{v['ns_per_flight_step']:.0f} | {v['gflops']:.2f} | {100 * v['gflops'] / pk1:.1f} % |"
          for k, v in res["kernels"].items()], "",
        f"Agreement: sensitivities fwid vs flights-innermost {res['agreement']['fwid_vs_inner']:.1e}"
        f", hand vmap vs flights-innermost {res['agreement']['ref_vs_inner']:.1e} (relative); "
        f"outputs {res['agreement']['outputs']:.1e} (absolute).", "",
        f"## `fwid.fit_each` ({res['devices']} devices)", "",
        "| flights | min [s] | median [s] | Gauss-Newton steps (all flights) | GFLOP/s | of the "
        "machine |", "|---:|---:|---:|---:|---:|---:|",
        *[f"| {k} | {v['min_s']:.3f} | {v['median_s']:.3f} | {v['gn_steps_total']} | "
          f"{v['gflops']:.2f} | {100 * v['gflops'] / pk:.1f} % |"
          for k, v in sorted(res["fit_each"].items(), key=lambda kv: int(kv[0]))], "",
        "GFLOP/s: the arithmetic above divided by the minimum time (fit_each: Gauss-Newton "
        "steps x flops per step; its starts, checks and R relaxations are not counted, so "
        "this is what the step arithmetic alone would take at that rate).",
    ]
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=64)
    ap.add_argument("--rounds", type=int, default=30)
    ap.add_argument("--fit-repeats", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "simd.json"))
    M.run_and_write(run, markdown, ap.parse_args(argv))


if __name__ == "__main__":
    main()
