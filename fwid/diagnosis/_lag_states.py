"""`unsteady-aero`'s augmented model with its lags inside: the lagging part of the states made
from the model's own simulated states rather than read from the measured ones.

`augment` gives `unsteady-aero` the lagging part `lag(x) - x` of the axis's *measured* states
as prepared inputs (`u_lag`, `w_lag`, `q_lag`), as the output-error fit (Eqs. 10-11) reads
them from the flight. A model that has to predict a flight not yet flown (the discriminating
design) has no measured states: the lag becomes a state `z_s` per lagged state `x_s`,

    dz_s/dt = (x_s - z_s) / tau,

started steady (`z_s = x_s`), and the term `z_s - x_s` enters the loads through the fitted
coefficients (`Mw_lag`, ...) exactly where the prepared input did. The outputs stay those of
the model with inputs (the extra states are not outputs), so both models of a discriminating
pair compare the same outputs.

The other extra inputs of the augmented models are not functions of this axis's states (the
other axis's states, the flapping frequency, the time): they stay inputs.
"""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..models import GreyBoxModel
from ._signals import AXIS_STATES


class _Internal(eqx.Module):
    """`fn(x, u, p, c)` of the model with inputs (its state equation `rates=True`, output
    equation or force model `rates=False`), evaluated on the first `n` states, with the
    model's inputs rebuilt: the remaining ones from `u` (at `keep`), the lag inputs (at
    `slots`) as `z - x[src]`; with `rates`, the lag states' rates appended."""

    fn: Callable | None = eqx.field(static=True)  # None: the identity output
    n: int = eqx.field(static=True)
    src: tuple[int, ...] = eqx.field(static=True)
    slots: tuple[int, ...] = eqx.field(static=True)
    keep: tuple[int, ...] = eqx.field(static=True)
    tau: float = eqx.field(static=True)
    rates: bool = eqx.field(static=True)

    def __call__(self, x, u, p, c):
        xs, z = x[: self.n], x[self.n:]
        lagging = xs[np.asarray(self.src, dtype=int)]
        if self.fn is None:
            return xs
        full = jnp.zeros(len(self.keep) + len(self.slots), dtype=x.dtype)
        if self.keep:
            full = full.at[np.asarray(self.keep, dtype=int)].set(u)
        full = full.at[np.asarray(self.slots, dtype=int)].set(z - lagging)
        out = self.fn(xs, full, p, c)
        return jnp.concatenate([out, (lagging - z) / self.tau]) if self.rates else out


def lag_states(model: GreyBoxModel, axis: str, tau: float) -> GreyBoxModel:
    """The augmented model `model` (from `augment(axis, [("unsteady-aero", tau), ...])`, fitted
    or not) with its lag inputs `{s}_lag` replaced by lag states `{s}_lagged`.

    **Arguments:**
    - `model`: the augmented model; its inputs `u_lag`, ... (`AXIS_STATES[axis]`) are
      `lag(x) - x` of its own states through a first-order lag of `tau`.
    - `axis`: `"lon"` or `"lat"`.
    - `tau`: the diagnosed time constant [s].

    **Returns:** a [`fwid.GreyBoxModel`][] with the states `model.states` then one lag state per
    lagged state (start them at the lagged state, e.g. zero at trim), the inputs `model`'s
    other inputs, the same parameters, outputs and force names.
    """
    tau = float(tau)
    if not tau > 0:
        raise ValueError(f"lag_states: the time constant must be positive, got {tau}")
    lagged = [s for s in AXIS_STATES[axis] if f"{s}_lag" in model.inputs]
    if not lagged:
        raise ValueError(f"lag_states: {model.name} has no lag inputs "
                         f"({', '.join(f'{s}_lag' for s in AXIS_STATES[axis])})")
    slots = tuple(model.inputs.index(f"{s}_lag") for s in lagged)
    keep = tuple(k for k in range(len(model.inputs)) if k not in slots)
    src = tuple(model.states.index(s) for s in lagged)
    n = len(model.states)

    def wrap(fn, rates):
        return _Internal(fn, n, src, slots, keep, tau, rates)

    return GreyBoxModel(
        wrap(model.f, True), states=model.states + tuple(f"{s}_lagged" for s in lagged),
        inputs=tuple(model.inputs[k] for k in keep),
        params={k: model.params[k] for k in model.param_names},
        h=wrap(None if model.outputs_are_states else model.h, False), outputs=model.outputs,
        free=model.free, constants=model.constants,
        forces=None if model.forces is None else wrap(model.forces, False),
        force_names=model.force_names, local=model.local, name=model.name + "(lag states)")


def _lagged(x, dt: float, tau: float):
    """`x` through the first-order lag of `_catalogue.lagged` (the same recursion, in JAX:
    `y_k = a y_k-1 + (1 - a) (x_k + x_k-1) / 2`, started steady)."""
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
    `y`, then for a `lag_states` model its lag states, the lagged states through the lag
    `augment` prepares the lag inputs with (`_catalogue.lagging_part` plus the state).

    **Returns:** `(n, states)`.
    """
    n = len(model.outputs)
    if model.states[:n] != model.outputs:
        raise ValueError(f"states_along: {model.name}'s first states are not its outputs")
    if len(model.states) == n:
        return y
    f = model.f
    z = jnp.stack([_lagged(y[:, s], dt, f.tau) for s in f.src], axis=1)
    return jnp.concatenate([y, z], axis=1)
