"""The combined (full, time-varying) model: cycle-averaged plus flapping aerodynamics in the
equations of motion, Eqs. (13)-(15) in Eq. (7).

$$X = X_{TA}(\\Delta q, \\Delta u, \\Delta w, \\Delta\\delta_e) + X_{TV}(\\varphi), \\quad
Z = Z_{TA} + Z_{TV}, \\quad M = M_{TA} + M_{TV}$$

The time-varying part depends on the measured flapping phase only (an input), not on the
states; the sum enters the EOM, so the flapping shows in the simulated states (Section VI).
The trim terms of Eqs. (13)-(14) (`m g sin(theta0)`, `-m g cos(theta0)`) balance gravity at
trim and drop out of the perturbation EOM of fwid's cycle-averaged models.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ._fourier import fourier_series, fourier_structure
from ._greybox import GreyBoxModel


def _lon_force_map(c) -> Float[Array, "4 3"]:
    """How `(X, Z, M)` enter `(q, u, w, theta)'` in Eq. (7)."""
    m, Iy = c["mass"], c["Iy"]
    z = jnp.zeros_like(m)
    return jnp.stack([
        jnp.stack([z, z, 1.0 / Iy]),
        jnp.stack([1.0 / m, z, z]),
        jnp.stack([z, 1.0 / m, z]),
        jnp.stack([z, z, z]),
    ])


def _lat_force_map(c) -> Float[Array, "4 3"]:
    """How `(Y, L, N)` enter `(p, r, v, phi)'` in Eq. (8)."""
    Ix, Iz, Ixz, m = c["Ix"], c["Iz"], c["Ixz"], c["mass"]
    Ic = Ix * Iz - Ixz**2
    z = jnp.zeros_like(m)
    return jnp.stack([
        jnp.stack([z, Iz / Ic, Ixz / Ic]),
        jnp.stack([z, Ixz / Ic, Ix / Ic]),
        jnp.stack([1.0 / m, z, z]),
        jnp.stack([z, z, z]),
    ])


_FORCE_MAPS = {
    (("q", "u", "w", "theta"), ("X", "Z", "M")): _lon_force_map,
    (("p", "r", "v", "phi"), ("Y", "L", "N")): _lat_force_map,
}


class _Combined:
    """The state, output and force functions of a combined model (hashable, equal by parts,
    so equal models reuse compiled code)."""

    def __init__(self, cycle: GreyBoxModel, outputs, harmonics, force_map):
        self.cycle_f = cycle.f
        self.cycle_forces = cycle.forces
        self.n_in = len(cycle.inputs)
        self.force_names = cycle.force_names
        self.outputs = tuple(outputs)
        self.harmonics = int(harmonics)
        self.force_map = force_map
        # column of each Fourier output in the cycle model's force vector
        self.index = tuple(cycle.force_names.index(o) for o in outputs)

    def _key(self):
        return (self.cycle_f, self.cycle_forces, self.n_in, self.force_names, self.outputs,
                self.harmonics, self.force_map)

    def __eq__(self, other):
        return type(other) is type(self) and other._key() == self._key()

    def __hash__(self):
        return hash(self._key())

    def flapping(self, u, p):
        """`F_TV` (Eq. 12) as a vector over the cycle model's force names."""
        tv = fourier_series(u[self.n_in], p, self.outputs, self.harmonics)
        full = jnp.zeros(len(self.force_names), dtype=tv.dtype)
        return full.at[jnp.asarray(self.index)].set(tv)


class _CombinedF(_Combined):
    def __call__(self, x, u, p, c):
        xdot_ta = self.cycle_f(x, u[: self.n_in], p, c)
        return xdot_ta + self.force_map(c) @ self.flapping(u, p)


class _CombinedForces(_Combined):
    def __call__(self, x, u, p, c):
        return self.cycle_forces(x, u[: self.n_in], p, c) + self.flapping(u, p)


def combined(
    cycle_model: GreyBoxModel,
    fourier_model: GreyBoxModel,
    *,
    force_map=None,
    name: str = "combined",
) -> GreyBoxModel:
    """The full time-varying model: Eqs. (13)-(15) inserted into the EOM, Eq. (7).

    **Arguments:**
    - `cycle_model`: the cycle-averaged model (e.g. an identified [`fwid.longitudinal`][] or
      [`fwid.lateral`][]), with its force model (Eqs. 1-6).
    - `fourier_model`: a [`fwid.models.fourier_model`][] whose outputs are among the cycle
      model's force names (the others get no time-varying part).
    - `force_map`: `c -> (states, forces)` matrix saying how a force adds to the state
      derivatives; known for the DelFly longitudinal and lateral models (Eqs. 7, 8).
    - `name`: the model's name in reports.

    **Returns:** a [`fwid.GreyBoxModel`][] with the cycle model's states (and outputs), inputs
    the cycle model's inputs followed by `phase`, the parameters of both models (free: both
    models' free parameters), the cycle model's constants and local (bias) parameters, and
    `forces` the total aerodynamic forces and moments `F_TA + F_TV` (Eqs. 13-15).
    """
    outputs, harmonics = fourier_structure(fourier_model)
    missing = [o for o in outputs if o not in cycle_model.force_names]
    if missing:
        raise ValueError(
            f"combined: the Fourier model's outputs {missing} are not forces of the "
            f"{cycle_model.name!r} model (it has {cycle_model.force_names})"
        )
    if cycle_model.forces is None:
        raise ValueError(f"combined: the {cycle_model.name!r} model has no force model")
    if force_map is None:
        force_map = _FORCE_MAPS.get((cycle_model.states, cycle_model.force_names))
        if force_map is None:
            raise ValueError(
                f"combined: no force map known for states {cycle_model.states} and forces "
                f"{cycle_model.force_names}; pass force_map=c -> (states x forces) matrix"
            )
    if not cycle_model.outputs_are_states:
        raise ValueError("combined: the cycle-averaged model must output its states")
    clash = set(cycle_model.params) & set(fourier_model.params)
    if clash:
        raise ValueError(f"combined: parameter names used by both models: {sorted(clash)}")
    params = {**cycle_model.params, **fourier_model.params}
    return GreyBoxModel(
        _CombinedF(cycle_model, outputs, harmonics, force_map),
        states=cycle_model.states,
        inputs=tuple(cycle_model.inputs) + ("phase",),
        params=params,
        free=tuple(cycle_model.free) + tuple(fourier_model.free),
        constants=cycle_model.constants,
        forces=_CombinedForces(cycle_model, outputs, harmonics, force_map),
        force_names=cycle_model.force_names,
        local=cycle_model.local,
        name=name,
    )


def force_parts(
    model: GreyBoxModel, xs: Float[Array, "n nx"], exp, params=None
) -> tuple[Float[Array, "n nf"], Float[Array, "n nf"]]:
    """The two terms of Eqs. (13)-(15) along a simulated trajectory of a combined model.

    **Arguments:**
    - `model`: a model from [`fwid.models.combined`][].
    - `xs`: its simulated states, `(n, states)`.
    - `exp`: the [`fwid.Experiment`][] it was simulated on (inputs `..., phase`).
    - `params`: the parameters (default `model.params`).

    **Returns:** `(F_TA, F_TV)`, each `(n, force_names)`: the cycle-averaged aerodynamics of
    the simulated states and the Fourier series of the measured phase (Figure 15).
    """
    if not isinstance(model.f, _CombinedF):
        raise ValueError(f"model {model.name!r} is not a combined model")
    p = model.params if params is None else params
    comb = model.f
    ta = jax.vmap(lambda x, u: comb.cycle_forces(x, u[: comb.n_in], p, exp.consts))(xs, exp.u)
    tv = jax.vmap(lambda u: comb.flapping(u, p))(exp.u)
    return ta, tv
