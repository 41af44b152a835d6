"""Parallel in time: the RK4 solution of a model affine in its state as a prefix composition of
affine maps (`jax.lax.associative_scan`), `log2(n)` dependent rounds instead of `n`.

For `x' = f(x, u, args)` affine in `x` (for each input and argument, e.g. `A x + B u + b`,
`A` may depend on the input), one RK4 step of [`fwid.RK4`][] with the input linear over the
step is an affine map `x_{k+1} = Phi_k x_k + c_k` with `Phi_k` its Jacobian and `c_k` the step
from `x = 0`, each computed for every interval at once. Composing the pairs,
`(P2, c2) o (P1, c1) = (P2 P1, P2 c1 + c2)`, gives every sample's state from `x_0`. Exact
arithmetic gives the sequential scan's numbers; in floating point they agree to round-off
(the sums are taken in another order).
"""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from ._rk4 import step_interval

# primitives that keep a value affine in the state whatever their operands (shape, layout,
# sums, the state's linear combinations)
_LINEAR = {
    "add", "sub", "neg", "reduce_sum", "broadcast_in_dim", "reshape", "squeeze",
    "expand_dims", "transpose", "slice", "concatenate", "convert_element_type", "copy",
    "copy_p", "add_any", "pad", "rev", "select_n", "dynamic_slice", "gather", "cumsum",
    "real", "imag", "stop_gradient", "stack", "split", "dynamic_update_slice",
}
# affine when only one operand depends on the state (a product with a constant)
_PRODUCT = {"mul", "dot_general"}


def _affine_jaxpr(jaxpr, depends: list[bool]) -> bool:
    """Whether every output of `jaxpr` is affine in the inputs marked in `depends` (the
    others held fixed): a walk over its equations, sound but conservative (an operation not
    known to keep affinity makes the answer False)."""
    dep = {v: d for v, d in zip(jaxpr.invars, depends)}

    def d_of(a):
        return dep.get(a, False) if not hasattr(a, "val") else False

    for eqn in jaxpr.eqns:
        ins = [d_of(a) for a in eqn.invars]
        out = any(ins)
        name = eqn.primitive.name
        if not out:
            pass
        elif name in _LINEAR:
            if name == "select_n" and ins[0]:
                return False  # a branch chosen by the state
            if name in ("dynamic_slice", "gather") and any(ins[1:]):
                return False  # an index from the state
        elif name in _PRODUCT:
            if sum(ins) > 1:
                return False
        elif name == "div":
            if ins[1]:
                return False
        elif name in ("pjit", "jit", "closed_call", "core_call", "custom_jvp_call",
                      "custom_vjp_call", "remat"):
            inner = eqn.params.get("jaxpr") or eqn.params.get("call_jaxpr") \
                or eqn.params.get("fun_jaxpr")
            if inner is None:
                return False
            inner = getattr(inner, "jaxpr", inner)
            if not _affine_jaxpr(inner, ins):
                return False
        else:
            return False
        for v in eqn.outvars:
            dep[v] = out
    return True


def affine_in_state(f: Callable, y, u, args=None) -> bool:
    """Whether `f(y, u, args)` is affine in `y` for every `u` and `args`, from its jaxpr (only
    shapes are used: it works on traced values too). Conservative: False for anything it
    cannot show affine (a state-dependent branch, a product of two states, `sin(x)`, ...)."""
    spec = lambda a: jax.ShapeDtypeStruct(jnp.shape(a), jnp.result_type(a))  # noqa: E731
    try:
        closed = jax.make_jaxpr(f)(jax.tree.map(spec, y), jax.tree.map(spec, u),
                                   jax.tree.map(spec, args))
    except Exception:  # noqa: BLE001 -- anything that does not trace on shapes alone
        return False
    n_y = len(jax.tree.leaves(y))
    n_rest = len(closed.jaxpr.invars) - n_y
    return _affine_jaxpr(closed.jaxpr, [True] * n_y + [False] * n_rest)


def parallel_wins() -> bool:
    """The measured rule: the associative scan is faster than the sequential one on an
    accelerator (thousands of lanes to spread the composition over), slower on a CPU (the
    composition does `O(n_states)` times the sequential scan's arithmetic; see
    `benchmarks/speed.py --parallel-time`)."""
    return jax.default_backend() != "cpu"


def use_parallel(time_parallel, f: Callable, y, u, args=None) -> bool:
    """Resolve the `time_parallel` option of a simulation: `True` (the model must be affine
    in its state), `False`, or `"auto"`: parallel where it wins (`parallel_wins`) and the
    model is affine in its state (`affine_in_state`)."""
    if time_parallel is True or time_parallel is False:
        if time_parallel and not affine_in_state(f, y, u, args):
            raise ValueError("time_parallel=True needs a model affine in its state (x' = A x"
                             " + B u + b); pass time_parallel='auto' or False for this model")
        return time_parallel
    if time_parallel != "auto":
        raise ValueError(f"time_parallel must be 'auto', True or False, not {time_parallel!r}")
    return parallel_wins() and affine_in_state(f, y, u, args)


def _compose(first, second):
    """`second o first` of affine maps `(P, c)`, batched over a leading axis; `c` a vector
    `(..., nx)` or a matrix `(..., nx, m)` (m right-hand sides)."""
    P1, c1 = first
    P2, c2 = second
    return _matmul(P2, P1), _matmul(P2, c1 if c1.ndim == P1.ndim else c1[..., None]).reshape(
        c2.shape) + c2


def _matmul(a, b):
    """Batched small matrix product as a broadcast multiply and sum: XLA fuses it with its
    neighbours, where a batched `dot_general` per level of the scan made the program take
    seconds to compile on a CPU."""
    return jnp.sum(a[..., :, :, None] * b[..., None, :, :], axis=-2)


def _prefix(Phi, c):
    """Every prefix composition of the steps `(Phi_k, c_k)`: the maps from sample 0 to
    samples 1.. n-1, `(n-1, nx, nx)` and `(n-1, nx, ...)`."""
    return lax.associative_scan(_compose, (Phi, c))


def _steps(f: Callable, y, t, u, args):
    """Each interval's step as an affine map of the state, `(Phi_k, c_k)`, all at once."""
    zero = jnp.zeros_like(y)

    def affine(ta, tb, ua, ub):
        step = lambda x: step_interval(f, x, ta, tb, ua, ub, args)  # noqa: E731
        return jax.jacfwd(step)(zero), step(zero)

    return jax.vmap(affine)(t[:-1], t[1:], u[:-1], u[1:])


@eqx.filter_jit
def solve_affine_at_samples(f: Callable, y0: Float[Array, " nx"], t: Float[Array, " n"],
                            u: Float[Array, "n nu"], args=None) -> Float[Array, "n nx"]:
    """The RK4 solution of `y' = f(y, u, args)`, affine in `y`, at every sample `(n, nx)`:
    the same steps as the sequential scan (`_simulate._solve_at_samples`), composed by
    `jax.lax.associative_scan`."""
    Phi, c = _steps(f, y0, t, u, args)  # (n-1, nx, nx), (n-1, nx)
    P, C = _prefix(Phi, c)
    ys = jnp.einsum("kij,j->ki", P, y0) + C
    return jnp.concatenate([y0[None], ys], axis=0)


@eqx.filter_jit
def solve_affine_sensitivities(f: Callable, y0: Float[Array, " nx"], t: Float[Array, " n"],
                               u: Float[Array, "n nu"], theta: Float[Array, " p"]
                               ) -> tuple[Float[Array, "n nx"], Float[Array, "n p nx"]]:
    """The RK4 solution of `y' = f(y, u, theta)`, affine in `y`, and its forward
    sensitivities `dy/dtheta` (`(n, p, nx)`, zero at the first sample), both parallel in
    time. The sensitivities follow the same steps, `S_{k+1} = Phi_k S_k + G_k` with
    `G_k = d step(y_k) / d theta` at the step's start (each known once the states are): a
    second associative scan over `(Phi_k, G_k)`, the numbers of the sequential scan of the
    state and its sensitivities to round-off."""
    Phi, c = _steps(f, y0, t, u, theta)
    P, C = _prefix(Phi, c)
    ys = jnp.concatenate([y0[None], jnp.einsum("kij,j->ki", P, y0) + C], axis=0)

    def forcing(y, ta, tb, ua, ub):
        return jax.jacfwd(lambda th: step_interval(f, y, ta, tb, ua, ub, th))(theta)

    G = jax.vmap(forcing)(ys[:-1], t[:-1], t[1:], u[:-1], u[1:])  # (n-1, nx, p)
    _, S = _prefix(Phi, G)
    S = jnp.concatenate([jnp.zeros_like(S[:1]), S], axis=0)
    return ys, jnp.swapaxes(S, 1, 2)
