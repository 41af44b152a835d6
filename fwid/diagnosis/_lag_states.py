"""`unsteady-aero`'s augmented model with its lags inside: the lagging part of the
quasi-steady loads made from the model's own simulated states rather than the measured ones.

`augment` gives `unsteady-aero` the lagging part of each load's quasi-steady load (the
diagnosed derivatives on the axis's measured states, through the diagnosed filter) as a
prepared input (`X_lag`, `Z_lag`, `M_lag`), as the output-error fit (Eqs. 10-11) reads them
from the flight. A model that has to predict a flight not yet flown (the discriminating
design) has no measured states: each filter stage becomes a state `z_lk` per load `l`,

    dz_lk/dt = (qs_l(x) - z_lk) / tau_k,    qs_l(x) = sum_s g_ls x_s,

started steady (`z = qs`), and the term `sum_k share_k z_lk + direct qs_l - qs_l` enters the
load through its fitted coefficient exactly where the prepared input did (one stage for a
first-order lag, two for the indicial form). A pure delay `T` has no finite state: it is
taken as its first-order Pade approximant `(1 - sT/2) / (1 + sT/2) = 2 / (1 + sT/2) - 1`, one
stage of `T/2` with share 2 and direct part -1 (an all-pass filter: the delay's gain, its
phase within 0.08 rad up to `1 / T` rad/s), enough for a design to tell it from its rivals. The
outputs stay those of the model with inputs (the extra states are not outputs), so both
models of a discriminating pair compare the same outputs.

The other extra inputs of the augmented models are not functions of this axis's states (the
other axis's states, the flapping frequency, the time): they stay inputs.
"""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..models import GreyBoxModel
from ._catalogue.unsteady_aero import WAGNER_RATIO, WAGNER_SHARES, Lagging
from ._signals import AXIS_LOADS


def stages(member: Lagging) -> tuple[tuple[float, ...], tuple[float, ...], float]:
    """The filter's first-order stages, their time constants and shares, and its direct part
    (the share of the input passed through: a delay's Pade approximant's -1; module
    docstring)."""
    if member.kind == "lag":
        return (member.tau,), (1.0,), 0.0
    if member.kind == "indicial":
        return (member.tau, WAGNER_RATIO * member.tau), WAGNER_SHARES, 0.0
    if member.kind == "delay":
        return (member.tau / 2.0,), (2.0,), -1.0
    raise ValueError(f"lag_states: a {member.text()} has no state form")


class _Internal(eqx.Module):
    """`fn(x, u, p, c)` of the model with inputs (its state equation `rates=True`, output
    equation or force model `rates=False`), evaluated on the first `n` states, with the
    model's inputs rebuilt: the remaining ones from `u` (at `keep`), the lag inputs (at
    `slots`) as `sum_k shares_k z_jk + (direct - 1) qs_j(x)` with `qs_j = weights_j . x`;
    with `rates`, the
    lag states' rates appended (slot-major: slot `j`'s stages are together)."""

    fn: Callable | None = eqx.field(static=True)  # None: the identity output
    n: int = eqx.field(static=True)
    weights: tuple[tuple[float, ...], ...] = eqx.field(static=True)
    slots: tuple[int, ...] = eqx.field(static=True)
    keep: tuple[int, ...] = eqx.field(static=True)
    taus: tuple[float, ...] = eqx.field(static=True)
    shares: tuple[float, ...] = eqx.field(static=True)
    rates: bool = eqx.field(static=True)
    direct: float = eqx.field(static=True, default=0.0)

    def __call__(self, x, u, p, c):
        xs = x[: self.n]
        if self.fn is None:
            return xs
        k = len(self.taus)
        z = x[self.n:].reshape(len(self.slots), k)
        qs = jnp.asarray(np.asarray(self.weights)) @ xs
        full = jnp.zeros(len(self.keep) + len(self.slots), dtype=x.dtype)
        if self.keep:
            full = full.at[np.asarray(self.keep, dtype=int)].set(u)
        full = full.at[np.asarray(self.slots, dtype=int)].set(
            z @ jnp.asarray(self.shares) + (self.direct - 1.0) * qs)
        out = self.fn(xs, full, p, c)
        if not self.rates:
            return out
        return jnp.concatenate([out, ((qs[:, None] - z) / jnp.asarray(self.taus)).ravel()])


def lag_states(model: GreyBoxModel, axis: str, member: Lagging) -> GreyBoxModel:
    """The augmented model `model` (from `augment(axis, [("unsteady-aero", member), ...])`,
    fitted or not) with its lag inputs `{load}_lag` replaced by lag states.

    **Arguments:**
    - `model`: the augmented model; its inputs `X_lag`, ... are the lagging parts of the
      quasi-steady loads (`member.derivatives`) through `member`'s filter.
    - `axis`: `"lon"` or `"lat"`.
    - `member`: the diagnosed filter (`Lagging`: a lag, the indicial form, or a delay as its
      Pade approximant).

    **Returns:** a [`fwid.GreyBoxModel`][] with the states `model.states` then the lag states
    (`{load}_lag{k}`: start them at the quasi-steady load, e.g. zero at trim), the inputs
    `model`'s other inputs, the same parameters, outputs and force names.
    """
    taus, shares, direct = stages(member)
    loads = [ld for ld in AXIS_LOADS[axis] if f"{ld}_lag" in model.inputs]
    if not loads:
        raise ValueError(f"lag_states: {model.name} has no lag inputs "
                         f"({', '.join(f'{ld}_lag' for ld in AXIS_LOADS[axis])})")
    slots = tuple(model.inputs.index(f"{ld}_lag") for ld in loads)
    keep = tuple(k for k in range(len(model.inputs)) if k not in slots)
    n = len(model.states)
    weights = tuple(tuple(float(member.derivatives.get(ld, {}).get(s, 0.0))
                          for s in model.states) for ld in loads)

    def wrap(fn, rates):
        return _Internal(fn, n, weights, slots, keep, tuple(taus), tuple(shares), rates, direct)

    return GreyBoxModel(
        wrap(model.f, True), states=model.states + tuple(
            f"{ld}_lag{k + 1}" for ld in loads for k in range(len(taus))),
        inputs=tuple(model.inputs[k] for k in keep),
        params={k: model.params[k] for k in model.param_names},
        h=wrap(None if model.outputs_are_states else model.h, False), outputs=model.outputs,
        free=model.free, constants=model.constants,
        forces=None if model.forces is None else wrap(model.forces, False),
        force_names=model.force_names, local=model.local, name=model.name + "(lag states)")


def jax_lag(x, dt: float, tau: float):
    """`x` through the first-order lag of `_catalogue._filters.lagged` (the same recursion,
    in JAX: `y_k = a y_k-1 + (1 - a) (x_k + x_k-1) / 2`, started steady)."""
    import jax

    a = np.exp(-dt / tau)

    def step(y, xs):
        y = a * y + (1.0 - a) * 0.5 * (xs[0] + xs[1])
        return y, y
    _, ys = jax.lax.scan(step, x[0], (x[:-1], x[1:]))
    return jnp.concatenate([x[:1], ys])


def states_along(model: GreyBoxModel, y, dt: float):
    """The full state of `model` along a trajectory `y` `(n, outputs)` of its outputs, for a
    model whose first states are its outputs (the lon/lat models and their augmentations):
    `y`, then for a `lag_states` model its lag states, each quasi-steady load through its
    stage's lag (the filter `augment` prepares the lag inputs with).

    **Returns:** `(n, states)`.
    """
    n = len(model.outputs)
    if model.states[:n] != model.outputs:
        raise ValueError(f"states_along: {model.name}'s first states are not its outputs")
    if len(model.states) == n:
        return y
    f = model.f
    qs = y @ jnp.asarray(np.asarray(f.weights))[:, :n].T
    z = [jax_lag(qs[:, j], dt, tau) for j in range(len(f.slots)) for tau in f.taus]
    return jnp.concatenate([y, jnp.stack(z, axis=1)], axis=1)
