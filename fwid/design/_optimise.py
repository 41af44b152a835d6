"""Gradient ascent over random restarts: Adam (optax), the restarts run side by side (`vmap`)."""

from __future__ import annotations

import time
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
from jaxtyping import Array, Float


def _say(progress, msg: str) -> None:
    if progress is True:
        print(f"fwid: {msg}", flush=True)
    elif callable(progress):
        progress(msg)


def minimise(loss: Callable[[Float[Array, " k"]], Float[Array, ""]],
             starts: Float[Array, "r k"], *, iterations: int = 300,
             learning_rate: float = 0.05, chunk: int = 50, progress=False,
             label: str = "design", args=None
             ) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """Minimise `loss` from each row of `starts` with Adam and a cosine-decaying step.

    **Arguments:**
    - `loss`: a scalar function of the unconstrained design variables, differentiable by
      `jax.grad` (reverse mode through the simulation); `loss(x, args)` where `args` is
      given (arrays the loss reads: passed to the compiled steps as arguments, not baked
      into them as constants, so that the compiled program is the same for every model of
      the same shapes and the persistent compilation cache serves it).
    - `starts`: the random restarts, one per row.
    - `iterations`: Adam steps per restart; `chunk`: steps per compiled scan (a progress
      line after each).
    - `progress`: `True` prints `fwid: ...` lines, a callable receives them.

    **Returns:** the best variables of every restart `(r, k)`, their losses `(r,)`, and the
    best loss after each chunk.
    """
    schedule = optax.cosine_decay_schedule(learning_rate, iterations, alpha=0.05)
    opt = optax.adam(schedule)
    if args is None:
        def loss_of(x, _):
            return loss(x)
    else:
        loss_of = loss
    value_and_grad = jax.value_and_grad(loss_of)

    def one(carry, args):
        x, state, best_x, best_f = carry
        f, g = value_and_grad(x, args)
        g = jnp.where(jnp.isfinite(g), g, 0.0)
        better = jnp.isfinite(f) & (f < best_f)
        best_x = jnp.where(better, x, best_x)
        best_f = jnp.where(better, f, best_f)
        upd, state = opt.update(g, state, x)
        return (optax.apply_updates(x, upd), state, best_x, best_f), None

    @eqx.filter_jit
    def run(carry, args):
        def steps(c):
            return jax.lax.scan(lambda c_, _: (one(c_, args)[0], None), c, None,
                                length=chunk)[0]
        return jax.vmap(steps)(carry)

    starts = jnp.asarray(starts, dtype=float)
    states = jax.vmap(opt.init)(starts)
    carry = (starts, states, starts, jnp.full(starts.shape[0], jnp.inf, dtype=starts.dtype))
    # the same types in as out, so that the compiled chunk is reused (no weak types)
    carry = jax.tree.map(lambda a: jnp.asarray(a, dtype=a.dtype), carry)
    history, t0 = [], time.perf_counter()
    carry = run(carry, args)
    carry = jax.tree.map(lambda a: jnp.asarray(a, dtype=a.dtype), carry)
    done = chunk
    while True:
        best = float(jnp.min(carry[3]))
        history.append(best)
        _say(progress, f"{label}: step {min(done, iterations)}/{iterations}, "
                       f"{starts.shape[0]} restarts, best criterion {-best:.4g} "
                       f"({time.perf_counter() - t0:.1f} s)")
        if done >= iterations:
            break
        carry = run(carry, args)
        done += chunk
    # the last iterate too
    f_last = eqx.filter_jit(jax.vmap(loss_of, in_axes=(0, None)))(carry[0], args)
    better = jnp.isfinite(f_last) & (f_last < carry[3])
    best_x = jnp.where(better[:, None], carry[0], carry[2])
    best_f = jnp.where(better, f_last, carry[3])
    return np.asarray(best_x), np.asarray(best_f), history
