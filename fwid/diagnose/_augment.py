"""The diagnosed effects inside the equations of motion: the grey-box model of Eqs. (7-8)
augmented, so that the output-error estimator (Eqs. 10-11) can re-fit it and the gap can be
measured where a user sees it, in the simulated states.

Each effect of the verdict becomes terms of the cycle-averaged model:

- `actuator-dynamics` (and the probe `input-lead`): the acting deflection, the measured one
  through the diagnosed lag or delay (a lead for the probe), replaces it as the model's input
  (`d_eff`, a prepared column; the time constant is the diagnosis's, the control derivative
  is re-estimated);
- `lon-lat-coupling`: the other axis's measured states and control as extra inputs, with a
  derivative per own load (`Xv`, `Mdr`, `Lq`, ...: Eqs. 1-6 with the cross terms);
- `nonlinear-aero`: the quadratic terms of `_catalogue.py` in the *simulated* states, with a
  coefficient per own load (`M_qq`, `Z_w|w|`, `X_uw`, ...);
- the probe `attitude`: a derivative of each own load on the attitude state (`Mtheta`).

The extra loads enter the EOM exactly as the aerodynamic ones do (divided by the mass, or
through the inertia matrix), and the force model used for the least-squares start carries
them too. `flap-coupling` acts on the flapping part, which the cycle-averaged simulation
does not contain: it is left out (the result says so).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import jax.numpy as jnp
import numpy as np

from ..data import Flight
from ..identify import get_model
from ..models import GreyBoxModel
from ._catalogue import lagged
from ._probes import ATTITUDE
from ._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, other

#: Effects (catalogue and probes) that have a form inside the cycle-averaged EOM.
IN_EOM = ("actuator-dynamics", "input-lead", "lon-lat-coupling", "nonlinear-aero", "attitude")


def _quadratic_terms(axis: str) -> list[tuple[str, Callable]]:
    xs = AXIS_STATES[axis]
    out = []
    for i, a in enumerate(xs):
        out.append((f"{a}{a}", lambda s, i=i: s[i] * s[i]))
        out.append((f"{a}|{a}|", lambda s, i=i: s[i] * jnp.abs(s[i])))
    for i in range(len(xs)):
        for j in range(i + 1, len(xs)):
            out.append((f"{xs[i]}{xs[j]}", lambda s, i=i, j=j: s[i] * s[j]))
    return out


def _load_rates(axis: str, dF, c):
    """State derivatives of extra loads `dF` (the axis's loads in `AXIS_LOADS` order), as the
    aerodynamic loads enter Eq. (7) (lon: q u w theta) or Eq. (8) (lat: p r v phi)."""
    if axis == "lon":
        dX, dZ, dM = dF
        return jnp.stack([dM / c["Iy"], dX / c["mass"], dZ / c["mass"], 0.0 * dM])
    dY, dL, dN = dF
    Ix, Iz, Ixz = c["Ix"], c["Iz"], c["Ixz"]
    Ic = Ix * Iz - Ixz**2
    return jnp.stack([(Iz * dL + Ixz * dN) / Ic, (Ixz * dL + Ix * dN) / Ic, dY / c["mass"],
                      0.0 * dY])


def augment(axis: str, effects: Sequence[tuple[str, object]]
            ) -> tuple[GreyBoxModel, Callable[[Flight], Flight], list[str]]:
    """The `axis` model (`fwid.longitudinal`/`fwid.lateral`) with `effects` (`(name,
    variant)` pairs as the diagnosis selected them) inside its EOM.

    **Returns:** `(model, prepare, left_out)`: `prepare(flight)` adds the columns the model
    reads (the acting deflection), `left_out` the effects that have no cycle-averaged form.
    """
    base = get_model(axis)
    loads = AXIS_LOADS[axis]
    state_index = {s: k for k, s in enumerate(base.states)}
    ctrl = AXIS_INPUT[axis]
    control = ctrl
    shift = None  # (kind, tau) applied to the control column
    extra_inputs: list[str] = []
    terms: list[tuple[str, Callable]] = []  # (suffix, g(x, u_extra)) per own load
    left_out = []
    for name, variant in effects:
        if name in ("actuator-dynamics", "input-lead"):
            shift = variant if name == "actuator-dynamics" else ("delay", -float(variant))
            control = f"{ctrl}_eff"
        elif name == "lon-lat-coupling":
            o = other(axis)
            for k, s in enumerate(AXIS_STATES[o] + (AXIS_INPUT[o],)):
                j = len(extra_inputs)
                extra_inputs.append(s)
                terms.append((s, lambda x, ue, j=j: ue[j]))
        elif name == "nonlinear-aero":
            xs_idx = [state_index[s] for s in AXIS_STATES[axis]]
            for suffix, g in _quadratic_terms(axis):
                terms.append((f"_{suffix}", lambda x, ue, g=g: g(x[jnp.array(xs_idx)])))
        elif name == "attitude":
            k = state_index[ATTITUDE[axis]]
            terms.append((ATTITUDE[axis], lambda x, ue, k=k: x[k]))
        else:
            left_out.append(name)
    new = [f"{ld}{suffix}" for suffix, _ in terms for ld in loads]

    def extra_loads(x, u, p):
        ue = u[1:]
        return [sum((p[f"{ld}{suffix}"] * g(x, ue) for suffix, g in terms), 0.0 * x[0])
                for ld in loads]

    def f(x, u, p, c):
        return base.f(x, u[:1], p, c) + _load_rates(axis, extra_loads(x, u, p), c)

    def forces(x, u, p, c):
        return base.forces(x, u[:1], p, c) + jnp.stack(extra_loads(x, u, p))

    params = {k: float(v) for k, v in base.params.items()}
    params.update({k: 0.0 for k in new})
    model = GreyBoxModel(
        f, states=base.states, inputs=(control, *extra_inputs), params=params,
        free=tuple(base.free) + tuple(new), constants=base.constants, forces=forces,
        force_names=base.force_names, local=base.local,
        name=base.name + "+" + "+".join(n for n, _ in effects if n not in left_out),
    )

    def prepare(flight: Flight) -> Flight:
        if shift is None:
            return flight
        d = np.asarray(flight[ctrl]) - float(flight.trim_value(ctrl))
        kind, tau = shift
        return flight.with_columns(**{control: lagged(d, flight.dt, kind, tau)})

    return model, prepare, left_out
