"""No silent failure on an unstable system: output error integrates the model open loop.

The output-error simulation (Sec. IV.B, Eq. 7) starts from `x0` and never looks at the
measured states again. When the identified dynamics are unstable, an error in a parameter or
in `x0` grows like `exp(lambda t)`: over a record many times the mode's time constant the
simulation diverges from the data for all but the exact parameters, the cost surface is
narrow and ragged, and from a poor start the fit settles on a stable model that is wrong
(FVSysID test case 8, `unStabAC_sim.asc`: lambda ~ +0.7 1/s over 12.5 s). Jategaonkar (2015,
Sec. 9.16) stabilises the simulation with the measured states, filter error (process noise)
or multiple shooting. [`instability_warning`][] says when the fitted model grows more than
[`GROWTH_MAX`][]-fold over its record.
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import numpy as np

from ..models._greybox import GreyBoxModel
from .._advice import advise

#: Warn when the fastest unstable mode grows more than this factor over the record.
GROWTH_MAX = 100.0


@eqx.filter_jit
def _state_matrix(model: GreyBoxModel, consts, x0, u0):
    """`A = df/dx` at `x0`, `u0`: compiled once per model (the parameters are arguments)."""
    return model.state_matrices(model.params, consts, x0, u0)[0]


def fastest_growth(model: GreyBoxModel, exp) -> float:
    """The largest real part of the eigenvalues of `A = df/dx` (1/s), linearised at the
    experiment's initial state and first input (the perturbation models' trim is near there;
    a model in absolute states needs a real flight condition, which `x0` is)."""
    if not model.states:
        return float("-inf")
    A = np.asarray(_state_matrix(model, exp.consts, exp.x0, exp.u[0]), dtype=float)
    if not np.all(np.isfinite(A)):
        return float("-inf")
    return float(np.max(np.linalg.eigvals(A).real))


def instability_warning(model: GreyBoxModel, exps: Sequence, flights: Sequence[str]
                        ) -> str | None:
    """The warning for a fitted `model` whose simulation grows more than [`GROWTH_MAX`][]-fold
    over the longest of `exps` (`None` when it does not)."""
    lam = max(fastest_growth(model, e) for e in exps[:1])
    T = max(float(np.sum(np.asarray(e.mask)) - 1) * float(e.t[1] - e.t[0]) for e in exps)
    if not lam > 0 or lam * T <= np.log(GROWTH_MAX):
        return None
    return (f"{', '.join(flights)}: the {model.name} model identified is unstable (eigenvalue "
            f"{lam:+.3g} 1/s, time to double {np.log(2) / lam:.3g} s): its open-loop simulation "
            f"grows {np.exp(lam * T):.3g}-fold over the {T:.3g} s record, so output error "
            "diverges from the data for all but the exact parameters and x0 and can settle "
            "on a wrong stable model; trust the estimates only if the residuals are small and "
            "white; otherwise use a method that keeps the simulation near the data, next: "
            f"{advise('unstable', 'output-error')}")
