"""`Experiment`: what the estimator and the simulator need of one flight, as arrays."""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._errors import FlightDataError
from ._checks import check_experiment, check_lengths, check_time_axis


class Experiment(eqx.Module):
    """One manoeuvre, ready to simulate: uniform time, inputs, measured outputs, initial state.

    **Fields:**
    - `t`: time [s], uniform step.
    - `u`: inputs, `(n, inputs)` (perturbations for the DelFly models).
    - `z`: measured outputs, `(n, outputs)`.
    - `x0`: initial state; omitted, the first sample of `z` (only right when the model's
      outputs are the states: [`fwid.fit`][] says so otherwise).
    - `consts`: per-flight constants the model reads (mass, inertia, trim).
    - `mask`: 1 on real samples, 0 on padding (see [`fwid.stack_experiments`][]).
    - `forces`: measured (reconstructed) aerodynamic forces `(n, force_names)` or `None`.
    """

    t: Float[Array, " n"]
    u: Float[Array, "n nu"]
    z: Float[Array, "n ny"]
    x0: Float[Array, " nx"]
    consts: dict[str, Float[Array, ""]]
    mask: Float[Array, " n"]
    forces: Float[Array, "n nf"] | None = None
    x0_from_z: bool = eqx.field(static=True, default=False)

    def __init__(self, t, u, z, x0=None, consts=None, mask=None, forces=None):
        if np.ndim(t) == 1 and mask is None:  # one experiment (not a padded batch): check t
            check_time_axis(t)
        self.t = jnp.asarray(t, dtype=float)
        u = jnp.asarray(u, dtype=float)
        self.u = u[:, None] if u.ndim == 1 else u
        z = jnp.asarray(z, dtype=float)
        self.z = z[:, None] if z.ndim == 1 else z
        if self.t.ndim == 1:
            check_lengths(self.t, self.u, self.z)
        self.x0_from_z = x0 is None
        self.x0 = self.z[0] if x0 is None else jnp.asarray(x0, dtype=float)
        self.consts = {k: jnp.asarray(v, dtype=float) for k, v in (consts or {}).items()}
        self.mask = jnp.ones(self.t.shape) if mask is None else jnp.asarray(mask, dtype=float)
        self.forces = None if forces is None else jnp.asarray(forces, dtype=float)

    @property
    def dt(self):
        return self.t[1] - self.t[0]

    @property
    def n(self) -> int:
        return int(self.t.shape[-1])


def experiment(flight, model, *, x0: str = "first") -> Experiment:
    """Build an [`fwid.Experiment`][] from a [`fwid.Flight`][] for `model`.

    States, outputs and inputs are taken as perturbations from the flight's trim (the paper's
    Delta quantities); the model's constants come from the vehicle and the trim; the measured
    forces are taken when the flight has them (for the least-squares start).

    **Arguments:**

    - `flight`: the flight (usually cycle-averaged first, see [`fwid.cycle_averaged`][]).
    - `model`: the [`fwid.GreyBoxModel`][].
    - `x0`: `"first"` takes the initial state from the first sample of the measured states.

    **Returns:** an [`fwid.Experiment`][].
    """
    cols = list(model.inputs) + list(model.outputs)
    if not model.outputs_are_states:
        cols += list(model.states)
    flight.require(dict.fromkeys(cols))
    u = jnp.stack([flight.perturbation(c) for c in model.inputs], axis=-1)
    z = jnp.stack([flight.perturbation(c) for c in model.outputs], axis=-1)
    xs = jnp.stack([flight.perturbation(c) for c in model.states], axis=-1)
    consts = {}
    vehicle = flight.vehicle.as_dict() if flight.vehicle is not None else {}
    for k in model.constants:
        if k in vehicle:
            consts[k] = vehicle[k]
        elif k in flight.trim:
            consts[k] = flight.trim[k]
        elif k in ("mass", "Ix", "Iy", "Iz", "Ixz", "g"):
            raise FlightDataError(
                f"{flight.name}: the {model.name} model needs the vehicle's '{k}' but no "
                "vehicle.json was found beside the flight; add one (the guide's 'Formats and "
                "interfaces' page, docs/reference/formats.md)"
            )
        else:
            raise FlightDataError(
                f"{flight.name}: the {model.name} model needs the trim value '{k}'; give "
                f"it in the sidecar {flight.name.rsplit('.', 1)[0]}.json as "
                f'{{"trim": {{"{k}": ...}}}} or add the column {k[:-1]!r}'
            )
    forces = None
    if model.force_names and all(c in flight for c in model.force_names):
        forces = jnp.stack([flight.perturbation(c) for c in model.force_names], axis=-1)
    exp = Experiment(flight.t, u, z, xs[0], consts, forces=forces)
    check_experiment(model, exp, flight.name)
    return exp


def with_measured_x0(model, exp: Experiment) -> Experiment:
    """`exp` with `x0` taken from the first sample of the measured states when it was not
    given and the model's states are among its outputs (`model.measured_states`, e.g. the
    states w, q of the outputs az, w, q); `exp` itself otherwise (where the outputs are the
    states `x0` is already `z[0]`; where the states are not measured, the check of
    [`check_experiment`][] asks for `x0`). `model`: a [`fwid.GreyBoxModel`][]."""
    idx = model.measured_states
    if not exp.x0_from_z or model.outputs_are_states or idx is None:
        return exp
    return Experiment(exp.t, exp.u, exp.z, x0=exp.z[0, np.asarray(idx)], consts=exp.consts,
                      mask=exp.mask, forces=exp.forces)


def stack_experiments(exps: Sequence[Experiment], n: int | None = None) -> Experiment:
    """Pad experiments to a common length and stack them along a leading batch axis.

    Time continues on the same uniform grid, inputs hold their last value and the mask is 0
    on the padding, so a padded sample never enters a cost or a metric.

    **Arguments:**

    - `exps`: the experiments, all of one model.
    - `n`: the common length (default: the longest experiment's).

    **Returns:** one [`fwid.Experiment`][] whose arrays have a leading batch axis.
    """
    n = max(e.n for e in exps) if n is None else n
    keys = sorted(set().union(*(e.consts for e in exps)))
    have_forces = all(e.forces is not None for e in exps)

    def pad(e: Experiment):
        k = n - e.n
        t = np.asarray(e.t)
        dt = t[1] - t[0]
        tpad = np.concatenate([t, t[-1] + dt * np.arange(1, k + 1)])

        def hold(a):
            a = np.asarray(a)
            return np.concatenate([a, np.repeat(a[-1:], k, axis=0)], axis=0)

        return dict(t=tpad, u=hold(e.u), z=hold(e.z), x0=np.asarray(e.x0),
                    consts={key: np.asarray(e.consts.get(key, np.nan)) for key in keys},
                    mask=np.concatenate([np.asarray(e.mask), np.zeros(k)]),
                    forces=hold(e.forces) if have_forces else None)

    padded = [pad(e) for e in exps]  # numpy throughout: one transfer per field at the end

    def stacked(field):
        return np.stack([p[field] for p in padded])

    return Experiment(
        stacked("t"), stacked("u"), stacked("z"), stacked("x0"),
        {key: np.stack([p["consts"][key] for p in padded]) for key in keys},
        stacked("mask"), stacked("forces") if have_forces else None,
    )


def unstack_experiments(batch: Experiment) -> list[Experiment]:
    """The inverse of [`fwid.stack_experiments`][]: one experiment per batch entry.

    **Arguments:**

    - `batch`: an [`fwid.Experiment`][] with a leading batch axis.

    **Returns:** the list of experiments, padding removed.
    """
    out = []
    for i in range(batch.t.shape[0]):
        n = int(np.asarray(batch.mask[i]).sum())
        out.append(Experiment(
            batch.t[i, :n], batch.u[i, :n], batch.z[i, :n], batch.x0[i],
            {k: v[i] for k, v in batch.consts.items()}, None,
            None if batch.forces is None else batch.forces[i, :n]))
    return out

