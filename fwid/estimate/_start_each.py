"""The least-squares start of every flight on its own, in one compiled, vmapped call.

[`least_squares_start`][] on one flight runs a few Gauss-Newton steps, each a compiled
residual and Jacobian and a least-squares solve on the host, flight after flight. For
[`fwid.fit_each`][], [`least_squares_start_each`][] does the same for all flights at once:
the flights are padded to a common length, one of a few (`fwid.simulation.bucket_length`;
a padded sample carries no weight) and the whole start, the force regression and then the state
regression, with the solves, is one XLA computation `vmap`ped over the flights: one
compilation per model and batch shape, not a dispatch per step and flight. The estimates
equal those of `least_squares_start` on each flight alone (to rounding).
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..models._greybox import GreyBoxModel
from ..simulation._buckets import bucket_length
from ..simulation._experiment import Experiment, stack_experiments
from ._regression import derivative as _derivative
from ._start_outputs import nominal_start

#: Gauss-Newton steps per regression, as in `least_squares_start`.
ITERS = 3


def _residual(fn, params, names, theta, e, target, scales):
    """`(target - fn(x, u, p, c)) / scales` over one flight's samples, flattened."""
    p = {**params, **dict(zip(names, theta))}
    return ((target - jax.vmap(lambda x, u: fn(x, u, p, e.consts))(e.z, e.u)) / scales).ravel()


def _gauss_newton(fn, params, names, e, target, scales):
    """`_gauss_newton_lstsq` of `least_squares_start` on one padded flight: rows of padded
    samples and non-finite rows get no weight, and the minimum-norm solve cuts singular
    values as numpy's `lstsq` does on the remaining rows."""
    theta = jnp.stack([params[k] for k in names])
    row_ok = jnp.repeat(e.mask > 0, target.shape[-1])

    def residual(th):
        return _residual(fn, params, names, th, e, target, scales)

    def step(_, theta):
        r, J = residual(theta), jax.jacfwd(residual)(theta)
        ok = row_ok & jnp.isfinite(r) & jnp.all(jnp.isfinite(J), axis=1)
        rcond = jnp.finfo(float).eps * jnp.maximum(ok.sum(), len(names))
        return theta + jnp.linalg.lstsq(jnp.where(ok[:, None], J, 0.0),
                                        jnp.where(ok, -r, 0.0), rcond=rcond)[0]

    theta = jax.lax.fori_loop(0, ITERS, step, theta)  # a loop, not unrolled: compiles once
    return {**params, **dict(zip(names, theta))}


@eqx.filter_jit
def _force_dependence(model, names, batch):
    """Per flight, whether the force model's output depends on each of `names` (nonzero
    Jacobian column at the model's values): `(flights, names)` booleans."""
    params = {k: jnp.asarray(v, dtype=float) for k, v in model.params.items()}

    def one(e):
        theta = jnp.stack([params[k] for k in names])
        J = jax.jacfwd(lambda th: _residual(model.forces, params, names, th, e, e.forces, 1.0)
                       )(theta)
        J = J * jnp.repeat(e.mask, e.forces.shape[-1])[:, None]
        return jnp.any(J != 0, axis=0)

    return jax.vmap(one)(batch)


@eqx.filter_jit
def _start_batch(model, force_names, rest_names, batch, xdots, force_scales, state_scales):
    """The start parameters of every flight of `batch`: the force regression on
    `force_names`, then the state regression on `rest_names` (either may be empty)."""
    params = {k: jnp.asarray(v, dtype=float) for k, v in model.params.items()}

    def one(e, xdot, fs, ss):
        p = params
        if force_names:
            p = _gauss_newton(model.forces, p, force_names, e, e.forces, fs)
        if rest_names:
            p = _gauss_newton(model.f, p, rest_names, e, xdot, ss)
        return p

    return jax.vmap(one)(batch, xdots, force_scales, state_scales)


def _hold(a: np.ndarray, n: int) -> np.ndarray:
    return np.concatenate([a, np.repeat(a[-1:], n - a.shape[0], axis=0)], axis=0)


def least_squares_start_each(model: GreyBoxModel,
                             exps: Sequence[Experiment]) -> list[GreyBoxModel]:
    """[`fwid.least_squares_start`][] on each experiment alone, all in one batched call.

    **Returns:** one start model per experiment, in order.
    """
    exps = list(exps)
    out: list[GreyBoxModel | None] = [None] * len(exps)
    free = tuple(model.free)
    with_forces = [i for i, e in enumerate(exps) if model.forces is not None
                   and e.forces is not None]
    groups: dict[tuple, list[int]] = {}
    if with_forces:  # which free parameters each flight's force model depends on
        batch = stack_experiments([exps[i] for i in with_forces],
                                  bucket_length(max(exps[i].n for i in with_forces)))
        dep = np.asarray(_force_dependence(model, free, batch))
        for i, row in zip(with_forces, dep):
            groups.setdefault(tuple(k for k, d in zip(free, row) if d), []).append(i)
    rest_of_none = [i for i in range(len(exps)) if i not in set(with_forces)]
    if rest_of_none:
        groups.setdefault(None, []).extend(rest_of_none)
    for force_free, idx in groups.items():
        force_free = force_free or ()
        rest = tuple(k for k in free if k not in force_free)
        if rest and not model.outputs_are_states:
            nominal_start(model, list(rest))
            rest = ()
        group = [exps[i] for i in idx]
        n = bucket_length(max(e.n for e in group))
        batch = stack_experiments(group, n)
        nf = len(model.force_names) if force_free else 0
        fscales = np.stack([np.asarray(e.forces).std(axis=0) + 1e-300 if nf
                            else np.ones(1) for e in group])
        if rest:
            xd = [_derivative(e.t, e.z) for e in group]
            sscales = np.stack([x.std(axis=0) + 1e-300 for x in xd])
            xdots = np.stack([_hold(x, n) for x in xd])
        else:
            sscales = np.ones((len(group), 1))
            xdots = np.zeros((len(group), 1, 1))
        if not force_free and not rest:
            params = [dict(model.params)] * len(group)
        else:
            got = jax.device_get(_start_batch(model, force_free, rest, batch,
                                              jnp.asarray(xdots), jnp.asarray(fscales),
                                              jnp.asarray(sscales)))
            params = [{k: v[j] for k, v in got.items()} for j in range(len(group))]
        for j, i in enumerate(idx):
            out[i] = model.with_params(params[j])
    return out
