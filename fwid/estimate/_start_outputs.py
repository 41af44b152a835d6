"""Start values for models with an output equation `h`.

When every state is also measured (an output of the same name, e.g. the states p, r among
the outputs pdot, rdot, ay, p, r), [`output_equation_start`][] estimates the free
parameters by equation error on both equations at once: the numerically differentiated
measured states regressed on `f(x, u, p, c)` and the measured outputs regressed on
`h(x, u, p, c)`, both evaluated at the measured states and inputs (Jategaonkar 2015,
Sec. 6.2, the least-squares start of Sec. 9.16.1: `az = Zw w + Zq q + Zde de` regressed on
the measured w, q, de). Otherwise, and for the parameters that regression cannot reach, the
nominal values are kept and [`nominal_start`][] says so with a [`fwid.FitWarning`][] rather
than silently.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._errors import FitWarning
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ._regression import derivative, gauss_newton_lstsq, stacked


def output_equation_start(model: GreyBoxModel, exps: Sequence[Experiment], params: dict,
                          free: Sequence[str]) -> tuple[dict, list[str]]:
    """Equation error on `f` and `h` at the measured states (`model.measured_states`).

    Each channel is scaled by its standard deviation over the flights; the parameters enter
    through `f` (state derivatives) or `h` (outputs) or both, and a few Gauss-Newton steps of
    a minimum-norm least-squares solve find them (exactly when they enter linearly).

    **Returns:** `(params, kept)`: the parameters with the free ones `free` set, and those of
    `free` that neither equation depends on at the data (kept at their nominal values).
    """
    idx = np.asarray(model.measured_states)
    xexps = [eqx.tree_at(lambda e: e.z, e, e.z[:, idx]) for e in exps]
    xdots = [jnp.asarray(derivative(e.t, e.z)) for e in xexps]
    zs = [e.z for e in exps]
    tiny = 1e-300
    f_rj = stacked(model.f, params, free, xexps, xdots,
                   np.concatenate([np.asarray(x) for x in xdots]).std(axis=0) + tiny)
    h_rj = stacked(model.h, params, free, xexps, zs,
                   np.concatenate([np.asarray(z) for z in zs]).std(axis=0) + tiny)

    def both(theta):
        (rf, Jf), (rh, Jh) = f_rj(theta), h_rj(theta)
        return np.concatenate([rf, rh]), np.concatenate([Jf, Jh])

    theta0 = jnp.stack([jnp.asarray(params[k], dtype=float) for k in free])
    _, J = both(theta0)
    reached = np.any(np.nan_to_num(J) != 0, axis=0)
    theta = gauss_newton_lstsq(both, theta0)
    if not np.all(np.isfinite(np.asarray(theta))):
        return params, list(free)
    out = dict(params)
    out.update({k: v for k, v, ok in zip(free, theta, reached) if ok})
    return out, [k for k, ok in zip(free, reached) if not ok]


def nominal_start(model: GreyBoxModel, kept: Sequence[str]) -> None:
    """Warn that `kept` (free parameters of a model with an output equation and states)
    start at their nominal values."""
    if not kept or model.outputs_are_states or not model.states:
        return
    names = ", ".join(kept[:6]) + (f" and {len(kept) - 6} more" if len(kept) > 6 else "")
    if model.measured_states is None:
        why = ("the model has an output equation h and not all its states are outputs of the "
               "same name, so there are no measured states for the equation-error start to "
               "regress on")
    else:
        why = ("neither f nor h depends on them at the measured states, so the equation-error "
               "start cannot determine them")
    warnings.warn(
        f"{model.name}: the least-squares start keeps the nominal values of {names}: {why}; "
        "give start values (the model's params, or `start=model.with_params(...)`) close to "
        "the answer", FitWarning, stacklevel=4)
