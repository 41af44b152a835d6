"""What the sensitivities share: parameter sets, name checks, the output Jacobian.

The output Jacobian `dy/d(params | consts | x0)` is forward mode (`jax.jacfwd`) through the
diffrax simulation of Eq. 7 (Sec. IV.B): diffrax differentiates RK4 with
`diffrax.ForwardMode`, which supports forward mode only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp

from ..models._greybox import GreyBoxModel, Params
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate

_WRT = ("params", "consts", "x0")


def _full_params(model: GreyBoxModel, params: Mapping | None) -> Params:
    """`model.params` with the entries of `params` (all or some of them) put in."""
    out = dict(model.params)
    for k, v in (params or {}).items():
        if k not in out:
            raise KeyError(f"{model.name}: no parameter '{k}' (has {', '.join(model.param_names)})")
        out[k] = jnp.asarray(v, dtype=float)
    return out


def _check_single(exp: Experiment, what: str) -> None:
    if exp.t.ndim != 1:
        raise ValueError(f"{what}: give one experiment (t of shape (n,)), not a stacked batch "
                         f"of shape {tuple(exp.t.shape)}")


def _pick_names(available: Sequence[str], names: Sequence[str] | None, what: str) -> tuple:
    if names is None:
        return tuple(available)
    names = tuple(names)
    unknown = [k for k in names if k not in available]
    if unknown:
        raise KeyError(f"unknown {what} {unknown} (has {', '.join(available)})")
    return names


@eqx.filter_jit
def output_jacobian(model, exp, params, names: tuple, wrt: str):
    """`y` and `{name: dy/dname}` (each `(n, ny)`), by `jax.jacfwd` through the simulation."""

    def y_of(vals):
        if wrt == "params":
            return simulate(model, exp, {**params, **vals})[1]
        if wrt == "consts":
            e = eqx.tree_at(lambda e: e.consts, exp, {**exp.consts, **vals})
            return simulate(model, e, params)[1]
        x0 = jnp.stack([vals[k] for k in model.states])
        return simulate(model, exp, params, x0=x0)[1]

    if wrt == "params":
        vals = {k: params[k] for k in names}
    elif wrt == "consts":
        vals = {k: exp.consts[k] for k in names}
    else:
        vals = {k: exp.x0[i] for i, k in enumerate(model.states)}
    y = y_of(vals)
    S = jax.jacfwd(y_of)(vals)
    return y, {k: S[k] for k in names}
