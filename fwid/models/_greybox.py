"""`GreyBoxModel`: a state-space model `x' = f(x, u, p, c)`, `y = h(x, u, p, c)` plus metadata."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

Params = dict[str, Float[Array, ""]]


def _identity_output(x, u, p, c):
    return x


class GreyBoxModel(eqx.Module):
    """A grey-box model: pure functions of the state, input, parameters and constants.

    `f(x, u, p, c) -> x'` is the state equation and `h(x, u, p, c) -> y` the output equation
    (the identity, as in the paper, when `h` is `None`). `x` and `u` are 1-d arrays ordered as
    `states` and `inputs`; `p` is a dict of scalar parameters; `c` a dict of per-flight
    constants (mass, inertia, trim) that the [`fwid.Experiment`][] carries.

    A new model takes a few lines:

    ```python
    def f(x, u, p, c):
        alpha, q = x
        return jnp.stack([p["Z0"] + p["Za"] * alpha + (1 + p["Zq"]) * q + p["Zde"] * u[0],
                          p["M0"] + p["Ma"] * alpha + p["Mq"] * q + p["Mde"] * u[0]])

    model = fwid.GreyBoxModel(f, states=("alpha", "q"), inputs=("de",),
                              params=dict(Z0=0.0, Za=-1.0, Zq=0.0, Zde=0.0,
                                          M0=0.0, Ma=-1.0, Mq=-1.0, Mde=-1.0))
    ```

    **Arguments:**
    - `f`: the state equation.
    - `states`, `inputs`: names of the state and input channels.
    - `params`: the parameter names and their nominal (start) values.
    - `h`: the output equation; `None` means `y = x`.
    - `outputs`: names of the outputs (default: `states` when `h` is `None`).
    - `free`: the names of the parameters to estimate (default: all).
    - `constants`: names of the per-flight constants `c` that `f` and `h` read.
    - `forces`: optional `(x, u, p, c) -> array` giving the aerodynamic forces and moments
      (Eqs. 1-6) named by `force_names`; used for the least-squares start and the force plots.
    - `local`: parameters that belong to one flight rather than to the vehicle (the bias
      terms): re-estimated on each validation flight, and kept per flight in joint fits.
    - `name`: a short name used in reports (`"lon"`, `"lat"`, ...).
    """

    f: Callable = eqx.field(static=True)
    h: Callable = eqx.field(static=True)
    states: tuple[str, ...] = eqx.field(static=True)
    inputs: tuple[str, ...] = eqx.field(static=True)
    outputs: tuple[str, ...] = eqx.field(static=True)
    params: Params
    param_names: tuple[str, ...] = eqx.field(static=True)
    free: tuple[str, ...] = eqx.field(static=True)
    constants: tuple[str, ...] = eqx.field(static=True)
    forces: Callable | None = eqx.field(static=True)
    force_names: tuple[str, ...] = eqx.field(static=True)
    local: tuple[str, ...] = eqx.field(static=True)
    name: str = eqx.field(static=True)

    def __init__(
        self,
        f: Callable,
        *,
        states: Sequence[str],
        inputs: Sequence[str],
        params: Mapping[str, float],
        h: Callable | None = None,
        outputs: Sequence[str] | None = None,
        free: Sequence[str] | None = None,
        constants: Sequence[str] = (),
        forces: Callable | None = None,
        force_names: Sequence[str] = (),
        local: Sequence[str] = (),
        name: str = "model",
    ):
        self.f = f
        self.h = _identity_output if h is None else h
        self.states = tuple(states)
        self.inputs = tuple(inputs)
        if outputs is None:
            if h is not None:
                raise ValueError("GreyBoxModel: give `outputs` names when `h` is given")
            outputs = states
        self.outputs = tuple(outputs)
        self.params = {k: jnp.asarray(v, dtype=float) for k, v in params.items()}
        # JAX rebuilds dicts in sorted-key order, so the declared order is kept separately.
        self.param_names = tuple(params)
        free = tuple(params) if free is None else tuple(free)
        unknown = [k for k in free if k not in params]
        if unknown:
            raise ValueError(f"GreyBoxModel: free parameters {unknown} are not in `params`")
        self.free = tuple(k for k in params if k in free)  # in the declared order
        self.constants = tuple(constants)
        self.forces = forces
        self.force_names = tuple(force_names)
        self.local = tuple(k for k in local if k in params)
        self.name = name

    @property
    def outputs_are_states(self) -> bool:
        return self.h is _identity_output

    @property
    def measured_states(self) -> tuple[int, ...] | None:
        """The output column of each state, when every state is also an output of the same
        name (e.g. states p, r among outputs pdot, rdot, ay, p, r); `None` otherwise (and for
        a model without states)."""
        if not self.states or not all(s in self.outputs for s in self.states):
            return None
        return tuple(self.outputs.index(s) for s in self.states)

    def with_params(self, values: Mapping[str, float] | None = None, **kw) -> "GreyBoxModel":
        """A copy with some parameter values replaced."""
        new = dict(self.params)
        dtype = jnp.asarray(0.0).dtype
        for k, v in {**(values or {}), **kw}.items():
            if k not in new:
                raise KeyError(f"{self.name}: no parameter '{k}' (has {', '.join(new)})")
            # (a float scalar array already is what jnp.asarray would make: skip the dispatch)
            ready = isinstance(v, jax.Array) and v.dtype == dtype and v.ndim == 0
            new[k] = v if ready else jnp.asarray(v, dtype=float)
        return eqx.tree_at(lambda m: m.params, self, new)

    def with_free(self, free: Sequence[str]) -> "GreyBoxModel":
        """A copy that estimates only `free` (the other parameters stay at their values)."""
        return GreyBoxModel(
            self.f, states=self.states, inputs=self.inputs,
            params={k: self.params[k] for k in self.param_names},
            h=None if self.outputs_are_states else self.h,
            outputs=self.outputs, free=free, constants=self.constants, forces=self.forces,
            force_names=self.force_names, local=self.local, name=self.name,
        )

    # -- the free-parameter vector the estimator works on ---------------------------------
    def theta(self) -> Float[Array, " p"]:
        """The free parameters as a vector, in `free` order."""
        return jnp.stack([self.params[k] for k in self.free]) if self.free else jnp.zeros(0)

    def merge(self, theta: Float[Array, " p"], params: Params | None = None) -> Params:
        """The full parameter dict with the free ones taken from `theta`."""
        out = dict(self.params if params is None else params)
        for i, k in enumerate(self.free):
            out[k] = theta[i]
        return out

    def state_matrices(
        self, params: Params, consts: Mapping[str, Array],
        x0: Float[Array, " nx"] | None = None, u0: Float[Array, " nu"] | None = None,
    ) -> tuple[Float[Array, "nx nx"], Float[Array, "nx nu"]]:
        """`A = df/dx`, `B = df/du` (the linearised Eq. 7) at the point `x0`, `u0`.

        By default the point is `x = 0, u = 0`. For fwid's DelFly models (Eqs. 1-6), whose
        states and inputs are perturbations from the flight's trim, that *is* the trim. For a
        model in absolute states (e.g. one with the airspeed `V` as a state) `x = 0` is no
        flight condition at all: give the trim as `x0` (and `u0`).
        """
        x0 = jnp.zeros(len(self.states)) if x0 is None else jnp.asarray(x0, dtype=float)
        u0 = jnp.zeros(len(self.inputs)) if u0 is None else jnp.asarray(u0, dtype=float)
        if x0.shape != (len(self.states),) or u0.shape != (len(self.inputs),):
            raise ValueError(
                f"{self.name}: linearisation point x0 {tuple(x0.shape)} / u0 {tuple(u0.shape)} "
                f"must have shapes ({len(self.states)},) (states {', '.join(self.states)}) and "
                f"({len(self.inputs)},) (inputs {', '.join(self.inputs)})")
        return _jacobians(self.f, x0, u0, as_arrays(params), as_arrays(consts))

    def output_matrices(
        self, params: Params, consts: Mapping[str, Array],
    ) -> tuple[Float[Array, "ny nx"], Float[Array, "ny nu"]]:
        """`C = dh/dx`, `D = dh/du` of the output equation at `x = 0, u = 0` (the trim of
        fwid's perturbation models, as [`state_matrices`][])."""
        x0, u0 = jnp.zeros(len(self.states)), jnp.zeros(len(self.inputs))
        return _jacobians(self.h, x0, u0, as_arrays(params), as_arrays(consts))


def as_arrays(d: Mapping) -> dict:
    """Parameters or constants as float arrays: arguments of a compiled program rather than
    static values it would be compiled again for."""
    return {k: jnp.asarray(v, dtype=float) for k, v in d.items()}


@eqx.filter_jit
def _jacobians(f, x0, u0, params, consts):
    """`df/dx` and `df/du` (`f` the state or the output equation) at `x0`, `u0`: one compiled
    program per model and shape (op by op, the Jacobians cost a few dozen small
    compilations in every new process)."""
    return (jax.jacfwd(f, argnums=0)(x0, u0, params, consts),
            jax.jacfwd(f, argnums=1)(x0, u0, params, consts))
