"""Each flight fitted on its own: by output-error ML (Eqs. 10-11) all in one vmapped call, or
by another of [`fwid.fit`][]'s methods (`_fit.py`) flight by flight."""

from __future__ import annotations

import time
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import PartitionSpec

from .._errors import FitDivergedError
from ..models._greybox import GreyBoxModel
from ..simulation._buckets import bucket_length
from ..simulation._experiment import Experiment, stack_experiments, with_measured_x0
from ._devices import (
    device_count,
    flight_mesh,
    flights_per_call,
    onto_mesh,
    padded_count,
    spans_processes,
    to_host,
)
from . import _exported as exported
from ._fit import METHODS, fit
from ._noise import check_noise, fall_back
from ._output_error import _fit_batch, _result, with_instability
from ._prior import has_any, prior_bounds
from ._problem import FitResult, prepare
from ._start_each import least_squares_start_each
from ._warnings import issue


@eqx.filter_jit
def _fit_each_batched(model, theta0s, batches, prior=None, mesh=None, **kw):
    """[`_fit_batch`][] on each flight alone: `vmap` over the flights. With a device `mesh`
    (axis `"flights"`, see [`flight_mesh`][]) each device runs its share of the flights as
    its own `vmap` (`shard_map`: the fits are independent, the devices never wait for one
    another). A mesh that spans processes (`_distributed.py`) ends with an all-gather in the
    same program, so that every process holds every flight's output. `prior`: one prior and
    bounds ([`PriorBounds`][]) for every flight (replicated)."""
    if theta0s.shape[0] == 1:  # one flight: no vmap (it would batch the solvers' loops)
        out = _fit_batch(model, theta0s[0], jax.tree.map(lambda a: a[0], batches), prior, **kw)
        return jax.tree.map(lambda a: a[None], out)

    def each(th, b, pb):  # the sensitivities laid out for many flights (`paired`)
        return jax.vmap(lambda th1, b1: _fit_batch(model, th1, b1, pb, paired=True, **kw))(
            th, b)

    if mesh is None:
        return each(theta0s, batches, prior)
    spec = PartitionSpec("flights")
    specs = (spec, spec, PartitionSpec())
    if not spans_processes(mesh):
        return jax.shard_map(each, mesh=mesh, in_specs=specs, out_specs=spec,
                             check_vma=False)(theta0s, batches, prior)

    def each_gathered(th, b, pb):  # across processes: every device ends with every flight's
        return jax.tree.map(lambda a: jax.lax.all_gather(a, "flights", tiled=True),
                            each(th, b, pb))

    return jax.shard_map(each_gathered, mesh=mesh, in_specs=specs, out_specs=PartitionSpec(),
                         check_vma=False)(theta0s, batches, prior)


def fit_each(
    model: GreyBoxModel,
    experiments: Sequence[Experiment],
    *,
    names: Sequence[str] | None = None,
    start: str | GreyBoxModel = "least-squares",
    noise: str = "auto",
    max_passes: int = 12,
    max_steps: int = 60,
    rtol: float = 1e-10,
    cost_rtol: float = 1e-10,
    progress: bool = False,
    method: str = "output-error",
    prior=None,
    bounds=None,
    **options,
) -> list[FitResult]:
    """Fit `model` to each experiment on its own, all in one vmapped call (output error).

    The flights are padded to a common length, one of a few (`fwid.simulation.bucket_length`),
    and masked (a padded sample never enters a cost), so one compiled estimator serves every
    flight, and flights of a new length mostly reuse it, and the whole batch runs as a single
    XLA computation: no Python loop over flights. The estimates are those of [`fwid.fit`][]
    on each flight alone. Arguments as for [`fwid.fit`][].

    `method` and `options` pick the estimator as in [`fwid.fit`][]:
    `"output-error"` (the default) is the vmapped call above; `"multiple-shooting"` and
    `"filter-error"` are not vmapped (their Python-level loops: the segments' layout, the
    filter error's relaxation passes of R with the F compensation, Eq. 5.41) but run as
    [`fwid.fit`][] on each flight in turn, a Python loop over the flights, each with `start`
    as given (a least-squares start of its own per flight by default): their estimates are
    exactly those of [`fwid.fit`][] on each flight alone. `prior` and `bounds` (output
    error only) apply to every flight's fit alike.

    After [`fwid.initialize_distributed`][] on every process of a cluster, the same call on
    every process, with the same experiments, spreads the vmapped call over the devices of
    all processes, and every process gets every result.

    **Returns:** one [`fwid.FitResult`][] per experiment, in order (a
    [`fwid.FilterErrorResult`][] each with `method="filter-error"`).

    **Raises:** `ValueError` for an unknown `method` (naming the choices); otherwise as
    [`fwid.fit`][].
    """
    if method not in METHODS:
        raise ValueError(f"fit_each: method must be one of {', '.join(map(repr, METHODS))}, "
                         f"not {method!r}")
    if method != "output-error" or options:
        return _fit_each_looped(model, experiments, names=names, start=start, noise=noise,
                                max_passes=max_passes, max_steps=max_steps, rtol=rtol,
                                cost_rtol=cost_rtol, progress=progress, method=method,
                                prior=prior, bounds=bounds, **options)
    check_noise(noise)
    exps = [with_measured_x0(model, e) for e in experiments]
    names = list(names) if names is not None else [f"exp{i}" for i in range(len(exps))]
    t0 = time.perf_counter()
    pb = None  # without a prior or bounds: the plain fits' program
    if prior is not None or bounds is not None:
        pb = prior_bounds(model, list(model.free), prior, bounds)
        pb = pb if has_any(pb) else None
    if isinstance(start, str) and start == "least-squares":  # a start of its own per flight
        for e, n in zip(exps, names):  # the checks first, flight by flight
            prepare(model, [e], [n], "model", 0)
        starts = [prepare(model, [e], [n], s, 0)  # all starts in one batched call
                  for e, n, s in zip(exps, names, least_squares_start_each(model, exps))]
    else:  # one start for all (the checks still run on every flight)
        starts = [prepare(model, exps, names, start, 0)] * len(exps)
    if pb is not None:
        starts = [(m, pb.clip(th)) for m, th in starts]
    kw = dict(max_passes=max_passes, max_steps=max_steps, rtol=rtol, cost_rtol=cost_rtol)
    if progress:
        print(f"fwid: fitting {model.name} to {len(exps)} flights in one batched call"
              + (f" on {device_count()} devices" if device_count() > 1 else "") + " ...",
              flush=True)

    def run(idx: list[int], diagonal: bool) -> list:
        """The fits of flights `idx`: a FitResult each, or the FitDivergedError it raised
        (raised at once unless `noise="auto"`, which may still rescue it)."""
        outs = _run_batched(model, [exps[i] for i in idx], [starts[i][1] for i in idx],
                            diagonal, kw, pb)
        done = []
        for i, o in zip(idx, outs):
            try:
                done.append(_result(model, starts[i][0], starts[i][1], o, [names[i]], 0,
                                    max_steps, "diagonal" if diagonal else "full", pb))
            except FitDivergedError as e:
                if noise != "auto" or diagonal:
                    raise
                done.append(e)
        return done

    results = run(list(range(len(exps))), noise == "diagonal")
    if noise == "auto":
        results = fall_back(results, lambda idx: run(idx, True), [[n] for n in names], progress)
    results = [with_instability(r, [e], [n]) for r, e, n in zip(results, exps, names)]
    issue([w for r in results for w in r.warnings])
    if progress:
        ok = sum(bool(r.converged) for r in results)
        print(f"fwid: {ok}/{len(results)} fits converged, {time.perf_counter() - t0:.1f} s",
              flush=True)
    return results


def _fit_each_looped(model, experiments, *, names, progress, **kw) -> list[FitResult]:
    """[`fwid.fit`][] (any method, `kw` its arguments) on each experiment alone, in turn."""
    exps = list(experiments)
    names = list(names) if names is not None else [f"exp{i}" for i in range(len(exps))]
    if progress:
        print(f"fwid: fitting {model.name} to {len(exps)} flights one by one "
              f"({kw['method']})", flush=True)
    return [fit(model, e, names=[n], progress=progress, **kw) for e, n in zip(exps, names)]


def _run_batched(model, exps, theta0s, diagonal, kw, prior=None) -> list[dict]:
    """The raw estimator output of each flight, fitted alone, in batched calls: all flights
    at once, or, on CPU, in as few calls as keep to `flights_per_call` flights per device
    (larger batches of small LAPACK solves can hang jaxlib, see there), all of one shape so
    that one compiled program serves them."""
    n = bucket_length(max(e.n for e in exps))  # a few lengths: a new one rarely compiles
    per = flights_per_call(np.asarray(theta0s[0]).shape[-1])
    per = None if per is None else per * device_count()
    if per is None or len(exps) <= per:
        return _run_call(model, exps, theta0s, diagonal, kw, n, padded_count(len(exps)), prior)
    calls = -(-len(exps) // per)
    size = padded_count(-(-len(exps) // calls))  # balanced: as few copies as possible
    out = []
    for i in range(0, len(exps), size):
        out += _run_call(model, exps[i:i + size], theta0s[i:i + size], diagonal, kw, n, size,
                         prior)
    return out


def _run_call(model, exps, theta0s, diagonal, kw, n, B, prior=None) -> list[dict]:
    """One batched call on `B` flights of `n` samples. Every device gets the same number of
    flights: the batch is topped up with copies of the last flight, whose results are
    dropped. Across processes (`_distributed.py`) each process places its devices' share
    and gets every flight's output back."""
    fill = [exps[-1]] * (B - len(exps))
    stacked = jax.tree.map(lambda a: a[:, None], stack_experiments(exps + fill, n))
    th = jnp.asarray(np.stack([np.asarray(t) for t in list(theta0s) + list(theta0s[-1:]) * len(fill)]))
    mesh = flight_mesh(B)  # over every process's devices after initialize_distributed
    th, stacked = onto_mesh((th, stacked), mesh)
    out = to_host(exported.call(_fit_each_batched, (model, th, stacked, prior),
                                (False, True, True, False), mesh, diagonal=diagonal,
                                n_local_batch=0, **kw), mesh)
    # Sliced per flight on the host, then back as JAX arrays in one transfer (slicing device
    # arrays flight by flight costs more than the fits of a large batch).
    return jax.device_put([jax.tree.map(lambda x: x[i], out) for i in range(len(exps))])
