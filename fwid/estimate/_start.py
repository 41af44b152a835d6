"""Least-squares start values: equation error on the reconstructed forces (Sec. IV.B)."""

from __future__ import annotations

from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np

from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ._regression import derivative, gauss_newton_lstsq, stacked
from ._start_outputs import nominal_start, output_equation_start


def least_squares_start(model: GreyBoxModel, exps: Sequence[Experiment]) -> GreyBoxModel:
    """Start values for the output-error fit by linear regression (equation error).

    The paper regresses the reconstructed aerodynamic forces and moments on the measured
    states and inputs (Eqs. 1-6); fwid does that for every parameter that enters the force
    model when the flights carry the forces. The remaining free parameters (biases, or all of
    them for a model with no force model, such as the ATTAS short-period model) come from
    regressing the numerically differentiated measured states on `f(x, u, p, c)`; for a
    model with an output equation `h` whose states are all measured (outputs of the same
    name), jointly with regressing the measured outputs on `h(x, u, p, c)` at the measured
    states ([`output_equation_start`][]). Parameters the regression cannot reach keep their
    nominal values, with a [`fwid.FitWarning`][] that names them.

    **Returns:** the model with its free parameters set to the least-squares values.
    """
    free = list(model.free)
    params = dict(model.params)
    use_forces = model.forces is not None and all(e.forces is not None for e in exps)
    force_free: list[str] = []
    if use_forces:
        # Which free parameters does the force model depend on? (the first flight tells)
        e0 = exps[0]
        _, dF = stacked(model.forces, params, free, exps[:1], [e0.forces], 1.0)(
            jnp.stack([jnp.asarray(params[k], dtype=float) for k in free]))
        force_free = [k for i, k in enumerate(free) if np.any(dF[:, i] != 0)]

        scales = np.concatenate([np.asarray(e.forces) for e in exps]).std(axis=0) + 1e-300
        force_rj = stacked(model.forces, params, force_free, exps, [e.forces for e in exps],
                            scales)
        th = gauss_newton_lstsq(force_rj, jnp.stack([params[k] for k in force_free]))
        params.update(dict(zip(force_free, th)))

    rest = [k for k in free if k not in force_free]
    if rest and not model.outputs_are_states and model.measured_states is not None:
        params, kept = output_equation_start(model, exps, params, rest)
        nominal_start(model, kept)
    elif rest and model.outputs_are_states:
        xdots = [derivative(e.t, e.z) for e in exps]
        scales = np.concatenate(xdots).std(axis=0) + 1e-300
        state_rj = stacked(model.f, params, rest, exps, [jnp.asarray(x) for x in xdots],
                            scales)
        th = gauss_newton_lstsq(state_rj, jnp.stack([params[k] for k in rest]))
        params.update(dict(zip(rest, th)))
    else:
        nominal_start(model, rest)
    return model.with_params(params)
