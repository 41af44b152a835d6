"""Multiple shooting: output error that survives an unstable vehicle.

Plain output error integrates the model over the whole record from one initial state; an
unstable mode makes that simulation diverge (Jategaonkar 2015, Sec. 9.2). Multiple shooting
(Bock's method; Jategaonkar 2015, Sec. 9.11, "multiple shooting"; Bock, 1983) cuts each
record into short segments, integrates each from its own initial state `s_j`, estimated with
the parameters, and joins the segments by the continuity conditions

    d_j = x(t_{j+1}; s_j, theta) - s_{j+1} = 0,

so that no integration runs long enough to diverge. The unknowns are the free parameters and
the segment initial states (the first segment starts at the experiment's `x0`, as in plain
output error). Each Gauss-Newton step minimises the output-error likelihood (Eq. 10, R relaxed
by Eq. 11 at every step, as [`fwid.fit`][]) linearised, subject to the linearised continuity
conditions: the equality-constrained Gauss-Newton (KKT) system

    [H  D^T] [dtheta]   [-g]
    [D   0 ] [lambda] = [-d],   H = sum J^T R^-1 J,  g = sum J^T R^-1 v,  D = dd/dtheta,

with the step halved on the l1 merit function `cost + mu |d|_1`. At the solution the
segments join exactly and the estimates are those of output error on a trajectory that
follows the data. The Cramer-Rao covariance is the upper-left block of the inverse KKT
matrix (the information restricted to the constraint surface). Jacobians by forward-mode
autodiff through the RK4 integration of each segment (`fwid.estimate._steps`).

With `start="least-squares"` and the states measured, the fit starts from the equation-error
estimate (`fwid.estimate._equation_error`), which needs no simulation, as an unstable
vehicle flown in closed loop does.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate
from ._equation_error import equation_error_start
from ._gauss_newton import ml_cost, noise_covariance
from ._noise import check_noise, fall_back
from ._problem import FitResult, prepare
from ._uncertainty import correlation, lag1_autocorrelation
from ._warnings import fit_warnings, issue

_DEBUG = False  # print every accepted step (for development)
#: Default segment length, in sample intervals (0.5 s at 20 Hz): short enough that an unstable
#: mode grows little within a segment, long enough that the segment states stay few.
SEGMENT_SAMPLES = 10
#: ... and in seconds: a segment spans at least this long however fast the sampling (at
#: 100 Hz, 50 samples rather than 10: five times fewer segment states to estimate).
SEGMENT_SECONDS = 0.5


class _Segments(eqx.Module):
    """All segments of all experiments, padded to one length and stacked (axis 0)."""

    exp: Experiment  # t, u, z, mask (counted samples), consts, x0 (fixed start or guess)
    free_start: jax.Array  # (S,) index of the segment's start state in the vector, -1: fixed
    prev: jax.Array  # (C,) the segment whose end must meet ...
    nxt: jax.Array  # (C,) ... the start of this one


def _segments(model: GreyBoxModel, exps: Sequence[Experiment], n_segments: int):
    """Cut each experiment into `n_segments` (fewer for short ones) segments of equal length;
    segment j covers samples `b_j .. b_{j+1}` (its last sample is the next one's first; each
    sample is counted once). Returns the stacked segments and the start guesses of the free
    segment states (the measured state where a state is also an output, else `x0`)."""
    L = max(2, int(np.ceil((max(e.n for e in exps) - 1) / n_segments)))
    rows, guesses, prev, nxt, n_free = [], [], [], [], 0
    for e in exps:
        t, u, z = (np.asarray(a) for a in (e.t, e.u, e.z))
        mask = np.asarray(e.mask)
        n = int(mask.sum())
        dt = t[1] - t[0]
        S = max(1, int(np.ceil((n - 1) / L)))
        for j in range(S):
            b = j * L
            g = b + np.arange(L + 1)
            real = g < n
            gi = np.minimum(g, n - 1)
            counted = real & ((np.arange(L + 1) < L) | (g == n - 1))
            if j == 0:
                x0, idx = np.asarray(e.x0, dtype=float), -1
            else:
                x0 = np.array([z[b, model.outputs.index(s)] if s in model.outputs
                               else float(e.x0[i]) for i, s in enumerate(model.states)])
                idx = n_free
                n_free += len(model.states)
                guesses.append(x0)
                prev.append(len(rows) - 1)
                nxt.append(len(rows))
            rows.append(dict(t=t[0] + dt * g, u=u[gi], z=z[gi], mask=counted.astype(float),
                             x0=x0, idx=idx, consts=e.consts))
    keys = sorted(set().union(*(r["consts"] for r in rows)))
    exp = Experiment(
        np.stack([r["t"] for r in rows]), np.stack([r["u"] for r in rows]),
        np.stack([r["z"] for r in rows]), x0=np.stack([r["x0"] for r in rows]),
        consts={k: np.array([float(r["consts"].get(k, np.nan)) for r in rows]) for k in keys},
        mask=np.stack([r["mask"] for r in rows]))
    seg = _Segments(exp=exp, free_start=jnp.asarray([r["idx"] for r in rows]),
                    prev=jnp.asarray(prev, dtype=int), nxt=jnp.asarray(nxt, dtype=int))
    s0 = np.concatenate(guesses) if guesses else np.zeros(0)
    return seg, s0


def _residuals(model: GreyBoxModel, vec, seg: _Segments):
    """Output errors `(S, L+1, ny)` (zero where not counted) and continuity defects `(C, nx)`
    for the vector `[free parameters, free segment start states]`."""
    p = len(model.free)
    nx = len(model.states)
    params = model.merge(vec[:p])
    states = vec[p:]

    def one(e, idx):
        x0 = jnp.where(idx >= 0, jax.lax.dynamic_slice(
            jnp.concatenate([states, jnp.zeros(nx)]), (jnp.maximum(idx, 0),), (nx,)), e.x0)
        xs, ys = simulate(model, e, params, x0=x0)
        return (e.z - ys) * e.mask[:, None], xs[-1], x0

    v, xend, x0s = jax.vmap(one)(seg.exp, seg.free_start)
    d = xend[seg.prev] - x0s[seg.nxt]
    return v, d


@eqx.filter_jit
def _linearise(model, vec, seg, diagonal, floor):
    """Residuals, Jacobians, R (Eq. 11), the cost (Eq. 10) and the KKT step."""
    v, d = _residuals(model, vec, seg)
    Jv, Jd = jax.jacfwd(lambda x: _residuals(model, x, seg))(vec)
    ny = v.shape[-1]
    N = jnp.sum(seg.exp.mask)
    R = noise_covariance(v, N, diagonal, floor)
    Rinv = jnp.linalg.inv(R)
    vv = v.reshape(-1, ny)
    JJ = Jv.reshape(vv.shape[0], ny, -1)
    H = jnp.einsum("kip,ij,kjq->pq", JJ, Rinv, JJ)
    g = jnp.einsum("kip,ij,kj->p", JJ, Rinv, vv)
    D = Jd.reshape(-1, vec.shape[0])
    dd = d.reshape(-1)
    q, m = vec.shape[0], dd.shape[0]
    h = jnp.sqrt(jnp.diag(H))
    sc = jnp.where(h > 0, 1.0 / jnp.where(h > 0, h, 1.0), 1.0)  # unit-sensitivity scaling
    K = jnp.block([[H * sc[:, None] * sc[None, :], (D * sc[None, :]).T],
                   [D * sc[None, :], jnp.zeros((m, m))]])
    sol = jnp.linalg.solve(K, -jnp.concatenate([sc * g, dd]))
    step, lam = sc * sol[:q], sol[q:]
    Kinv = jnp.linalg.inv(K)
    cov = sc[:, None] * Kinv[:q, :q] * sc[None, :]  # constrained Cramer-Rao covariance
    return dict(v=v, d=dd, R=R, cost=ml_cost(R, N, ny), g=g, H=H, step=step, lam=lam,
                cov=cov, h=h)


@eqx.filter_jit
def _merit_parts(model, vec, seg, diagonal, floor):
    v, d = _residuals(model, vec, seg)
    N = jnp.sum(seg.exp.mask)
    c = ml_cost(noise_covariance(v, N, diagonal, floor), N, v.shape[-1])
    ok = jnp.isfinite(c) & jnp.all(jnp.isfinite(v)) & jnp.all(jnp.isfinite(d))
    return jnp.where(ok, c, jnp.inf), jnp.where(ok, jnp.sum(jnp.abs(d)), jnp.inf)


def _solve(model, seg, vec, *, diagonal, max_steps, rtol, cost_rtol, floor):
    """Equality-constrained Gauss-Newton with step halving on the l1 merit function."""
    hist = np.full(max_steps, np.nan)
    steps = accepted = 0
    converged = False
    lin = _linearise(model, vec, seg, diagonal, floor)
    xscale = float(jnp.max(jnp.abs(seg.exp.z))) + 1e-300
    dtol = 1e-12 * xscale * max(1, int(lin["d"].shape[0]))
    while steps < max_steps:
        mu = 2.0 * float(jnp.max(jnp.abs(lin["lam"]), initial=0.0)) + 1e-8
        c0 = float(lin["cost"])
        d0 = max(float(jnp.sum(jnp.abs(lin["d"]))) - dtol, 0.0)
        phi0 = c0 + mu * d0
        slope = float(lin["g"] @ lin["step"]) - mu * d0  # directional derivative of phi
        # the step in units of each unknown's standard deviation (about 1/h)
        in_std = jnp.abs(lin["step"]) * lin["h"]
        small = bool(jnp.all(in_std <= 1e-9 + rtol * jnp.abs(vec) * lin["h"])
                     | (jnp.max(in_std) <= 1e-6))
        # Converged when the continuity holds to round-off and the step promises a change of
        # the log-likelihood below 1e-5 (the estimates within ~0.005 std of the optimum):
        # near the optimum the steps only trade round-off between cost and continuity.
        if d0 == 0.0 and abs(slope) <= 1e-5 and accepted > 0:
            converged = True
            break
        alpha, ok = 1.0, False
        for _ in range(20):
            steps += 1
            c, d = (float(a) for a in _merit_parts(model, vec + alpha * lin["step"], seg,
                                                   diagonal, floor))
            d = max(d - dtol, 0.0)  # defects at round-off count as met
            tol = 1e3 * np.finfo(float).eps * (1.0 + abs(phi0))
            if np.isfinite(c) and (c + mu * d <= phi0 + 1e-4 * alpha * min(slope, 0.0) + tol):
                ok = True
                break
            if _DEBUG:
                print(f"    reject alpha {alpha:g}: dc {c - c0:.3g} d {d:.3g} d0 {d0:.3g} "
                      f"slope {slope:.3g} in_std {float(jnp.max(in_std)):.3g}")
            alpha *= 0.5
        if not ok:  # no step lowers the merit: converged when nothing is left to gain
            converged = small
            break
        vec = vec + alpha * lin["step"]
        if _DEBUG:
            print(f"  step {steps} alpha {alpha:g} cost {c:.8g} |d|_1 {d:.3g} mu {mu:.3g} "
                  f"small {small} theta {np.asarray(vec[:6]).round(4)}")
        hist[accepted] = c
        accepted += 1
        lin = _linearise(model, vec, seg, diagonal, floor)
        cont = float(jnp.max(jnp.abs(lin["d"]), initial=0.0))
        if (alpha == 1.0 and small and abs(c - c0) <= cost_rtol * (1 + abs(c))
                and cont <= 1e-8 * xscale):
            converged = True
            break
    return vec, lin, hist, steps, accepted, converged


def fit_shooting(
    model: GreyBoxModel,
    exps: Sequence[Experiment],
    *,
    names: Sequence[str],
    start="least-squares",
    noise: str = "auto",
    max_steps: int = 60,
    rtol: float = 1e-10,
    cost_rtol: float = 1e-10,
    progress: bool = False,
    segments: int | None = None,
):
    """[`fwid.fit`][] with `method="multiple-shooting"`: output error over `segments` segments
    per experiment (default: segments of [`SEGMENT_SAMPLES`][] samples and at least
    [`SEGMENT_SECONDS`][]) joined by continuity
    (see the module docstring). The model's `local`
    parameters are shared between the experiments. Returns a [`fwid.FitResult`][] whose
    `std` and `std_cr` are both the constrained Cramer-Rao bounds."""
    check_noise(noise)
    if segments is None:
        dt = min(float(e.dt) for e in exps)
        length = max(SEGMENT_SAMPLES, int(round(SEGMENT_SECONDS / dt)))
        segments = max(1, -(-(max(e.n for e in exps) - 1) // length))
    if not isinstance(segments, int) or segments < 1:
        raise ValueError(f"segments must be a positive integer, not {segments!r}")
    t0 = time.perf_counter()
    start, _ = equation_error_start(model, exps, names, start)
    start_model, theta0 = prepare(model, list(exps), list(names), start, 0)
    seg, s0 = _segments(model, exps, segments)
    vec0 = jnp.concatenate([theta0, jnp.asarray(s0, dtype=float)])
    z = seg.exp.z * seg.exp.mask[..., None]
    N = jnp.sum(seg.exp.mask)
    floor = (1e-9 * jnp.sqrt(jnp.sum(z**2, axis=(0, 1)) / N) + 1e-300) ** 2
    p = len(model.free)
    if progress:
        print(f"fwid: fitting {model.name} by multiple shooting ({int(seg.free_start.shape[0])}"
              f" segments) to {', '.join(names)} ...", flush=True)

    def run(diagonal: bool):
        vec, lin, hist, steps, accepted, converged = _solve(
            start_model, seg, vec0, diagonal=diagonal, max_steps=max_steps, rtol=rtol,
            cost_rtol=cost_rtol, floor=floor)
        theta = vec[:p]
        cov = lin["cov"][:p, :p]
        std = jnp.sqrt(jnp.abs(jnp.diag(cov)))
        v, mask = lin["v"], seg.exp.mask
        res = FitResult(
            model=start_model.with_params(dict(zip(model.free, theta))), names=model.free,
            theta=theta, std=std, std_cr=std, cov=cov, corr=correlation(cov), R=lin["R"],
            cost=lin["cost"], cost_history=jnp.asarray(hist), passes=jnp.asarray(accepted),
            steps=jnp.asarray(steps), converged=jnp.asarray(converged), start=theta0,
            noise="diagonal" if diagonal else "full",
            lag1=jnp.max(jax.vmap(lag1_autocorrelation)(v, mask), axis=0),
            residual_corr=correlation(jnp.einsum("bki,bkj->ij", v, v)))
        M = lin["H"][:p, :p]
        return dataclasses.replace(res, warnings=tuple(fit_warnings(res, names, max_steps, M,
                                                                   method="multiple-shooting")))

    if noise != "auto":
        result = run(noise == "diagonal")
    else:
        result = fall_back([run(False)], lambda idx: [run(True)], [names], progress)[0]
    issue(result.warnings, stacklevel=4)
    if progress:
        state = "converged" if bool(result.converged) else "NOT converged"
        print(f"fwid: multiple shooting {state} in {int(result.steps)} steps, "
              f"{time.perf_counter() - t0:.1f} s", flush=True)
    return result
