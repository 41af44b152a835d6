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


@eqx.filter_jit
def _chunk(loss, carry, learning_rate, iterations, chunk: int):
    """`chunk` Adam steps of every restart side by side. `loss` is a function (compiled
    again for each new one) or a callable pytree (an `equinox.Module`, e.g. the affine
    criterion: compiled once per static structure and shapes, its arrays traced)."""
    opt = _adam(learning_rate, iterations)

    def one(c, _):
        x, state, best_x, best_f = c
        f, g = jax.value_and_grad(loss)(x)
        g = jnp.where(jnp.isfinite(g), g, 0.0)
        better = jnp.isfinite(f) & (f < best_f)
        best_x = jnp.where(better, x, best_x)
        best_f = jnp.where(better, f, best_f)
        upd, state = opt.update(g, state, x)
        return (optax.apply_updates(x, upd), state, best_x, best_f), None

    return jax.vmap(lambda c: jax.lax.scan(one, c, None, length=chunk)[0])(carry)


@eqx.filter_jit
def _losses(loss, xs):
    return jax.vmap(loss)(xs)


def _adam(learning_rate, iterations, alpha: float = 0.05):
    """Adam with a cosine-decaying step from `learning_rate` to `alpha` of it over
    `iterations` (optax's `cosine_decay_schedule`, written out so that both may be traced:
    one compiled chunk serves any step size and length)."""
    def schedule(count):
        frac = jnp.minimum(count / iterations, 1.0)
        return learning_rate * (alpha + (1 - alpha) * 0.5 * (1 + jnp.cos(jnp.pi * frac)))
    return optax.adam(schedule)


def minimise(loss: Callable[[Float[Array, " k"]], Float[Array, ""]],
             starts: Float[Array, "r k"], *, iterations: int = 300,
             learning_rate: float = 0.05, chunk: int = 50, progress=False,
             label: str = "design") -> tuple[np.ndarray, np.ndarray, list[float]]:
    """Minimise `loss` from each row of `starts` with Adam and a cosine-decaying step.

    **Arguments:**
    - `loss`: a scalar function of the unconstrained design variables, differentiable by
      `jax.grad`; a callable `equinox.Module` keeps its arrays as arguments of the compiled
      steps (compiled once per structure and shapes, not for every model).
    - `starts`: the random restarts, one per row.
    - `iterations`: Adam steps per restart; `chunk`: steps per compiled scan (a progress
      line after each).
    - `progress`: `True` prints `fwid: ...` lines, a callable receives them.

    **Returns:** the best variables of every restart `(r, k)`, their losses `(r,)`, and the
    best loss after each chunk.
    """
    opt = _adam(learning_rate, iterations)
    starts = jnp.asarray(starts, dtype=float)
    states = jax.vmap(opt.init)(starts)
    carry = (starts, states, starts, jnp.full(starts.shape[0], jnp.inf, dtype=starts.dtype))
    # the same types in as out, so that the compiled chunk is reused (no weak types)
    carry = jax.tree.map(lambda a: jnp.asarray(a, dtype=a.dtype), carry)
    history, t0 = [], time.perf_counter()
    done = 0
    while done < iterations:
        carry = _chunk(loss, carry, jnp.asarray(float(learning_rate)),
                       jnp.asarray(float(iterations)), int(chunk))
        carry = jax.tree.map(lambda a: jnp.asarray(a, dtype=a.dtype), carry)
        done += chunk
        best = float(jnp.min(carry[3]))
        history.append(best)
        _say(progress, f"{label}: step {min(done, iterations)}/{iterations}, "
                       f"{starts.shape[0]} restarts, best criterion {-best:.4g} "
                       f"({time.perf_counter() - t0:.1f} s)")
    # the last iterate too
    f_last = _losses(loss, carry[0])
    better = jnp.isfinite(f_last) & (f_last < carry[3])
    best_x = jnp.where(better[:, None], carry[0], carry[2])
    best_f = jnp.where(better, f_last, carry[3])
    return np.asarray(best_x), np.asarray(best_f), history


@eqx.filter_jit
def _flipped(loss, x):
    k = x.shape[0]
    X = x[None, :] * (1.0 - 2.0 * jnp.eye(k, dtype=x.dtype))
    return jax.vmap(loss)(X)


def flip_search(loss: Callable[[Float[Array, " k"]], Float[Array, ""]],
                x: Float[Array, " k"], *, saturate: float = 30.0,
                rounds: int = 200) -> tuple[np.ndarray, float, int]:
    """Polish a piecewise-constant design as a bang-bang sequence: each step at the full
    amplitude with the sign of `x` (`tanh(30) = 1` to round-off), then single sign flips,
    the best one at a time, while one lowers `loss` (a greedy local search over the
    `2^k` sequences; every flip of a round is evaluated side by side).

    **Returns:** the polished variables, their loss and the number of flips made.
    """
    x = jnp.asarray(saturate * np.where(np.asarray(x) >= 0, 1.0, -1.0))
    f = float(_losses(loss, x[None])[0])
    flips = 0
    for _ in range(rounds):
        fs = np.asarray(_flipped(loss, x))
        j = int(np.argmin(fs))
        if not np.isfinite(fs[j]) or fs[j] >= f - 1e-12 * max(1.0, abs(f)):
            break
        x, f, flips = x.at[j].multiply(-1.0), float(fs[j]), flips + 1
    return np.asarray(x), f, flips
