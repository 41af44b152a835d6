"""The diagnosed effects inside the equations of motion: the grey-box model of Eqs. (7-8)
augmented, so that the output-error estimator (Eqs. 10-11) can re-fit it and the gap can be
measured where a user sees it, in the simulated states.

Each effect of the verdict becomes terms of the cycle-averaged model:

- `actuator-dynamics` and `time-offset`: the acting deflection, the cycle-averaged measured
  one through the diagnosed filter (a lead for `time-offset`), replaces it as the model's
  input (`d_eff`, a prepared column; the filter is the diagnosis's, the control derivative
  is re-estimated);
- `unsteady-aero`: per own load, the lagging part of its quasi-steady load (the diagnosed
  filter on the baseline's state load in the measured cycle-averaged states; prepared
  columns `X_lag`, ...) as an extra input of that load alone, with its coefficient
  (`X_lag`, ...);
- `flap-frequency`: the measured flapping frequency's deviation from its median, and its
  square, as extra inputs with a derivative per own load (`Xf`, `Xff`, ...); the frequency
  lag, when one was diagnosed, is applied to the prepared column;
- `lon-lat-coupling`: the other axis's measured states and control as extra inputs, with a
  derivative per own load (`Xv`, `Mdr`, `Lq`, ...: Eqs. 1-6 with the cross terms);
- `nonlinear-aero`: the diagnosed member's smooth functions (the diagnosis's own spline
  components, `_smooth.py`) of the *simulated* states, and their products, with a
  coefficient per own load (`M_w1`, `Z_q2`, `X_uw`, ...);
- the probe `attitude`: a derivative of each own load on the attitude state (`Mtheta`);
- the probe `drift`: the time since the flight's start (per 10 s) and its square as extra
  inputs, with a coefficient per own load (`Xtime`, `Xtime2`, ...), as the probe fits them.

The extra loads enter the EOM exactly as the aerodynamic ones do (divided by the mass, or
through the inertia matrix), and the force model used for the least-squares start carries
them too. `flap-coupling` acts on the flapping part, which the cycle-averaged simulation
does not contain: it is left out (the result says so).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..data import Flight
from ..identification import get_model
from ..models import GreyBoxModel
from ._catalogue import acting, actuator_filter, filter_text, frequency_deviation
from ._catalogue.nonlinear_aero import Terms
from ._catalogue.unsteady_aero import Lagging, lagging, quasi_steady
from ._probes import ATTITUDE, elapsed
from ._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, command, cycle_averaged, other

#: Effects (catalogue and probes) that have a form inside the cycle-averaged EOM.
IN_EOM = ("actuator-dynamics", "time-offset", "unsteady-aero", "flap-frequency",
          "lon-lat-coupling", "nonlinear-aero", "attitude", "drift")


def _term(kind: str, idx: tuple, x, ue):
    """One extra-load term: the extra input `ue[i]` (`"input"`), the state `x[i]`
    (`"state"`) or the product `x[i] x[j]` (`"cross"`), with `(i, j) = idx`. (A `"smooth"`
    term, the component `j` of its basis at `x[i]`, is evaluated in `Augmented`, once per
    state and call.)"""
    if kind == "input":
        return ue[idx[0]]
    if kind == "state":
        return x[idx[0]]
    return x[idx[0]] * x[idx[1]]


class Augmented(eqx.Module):
    """The augmented model's state equation (`rates=True`: Eqs. 7-8 with the extra loads
    entering as the aerodynamic ones do) or its loads (`rates=False`): `base(x, u[:1], p, c)`
    plus, on each of the axis's loads `ld`, the sum over `terms` (`(suffix, kind, indices,
    loads, basis)`, see `_term`; `loads` those it acts on, `()` all) of `p[ld + suffix]` times
    the term, the extra inputs being `u[1:]`.

    A module of static fields rather than a closure, so that the estimator's program for the
    augmented model is kept across processes like the baseline's (`fwid.estimate`'s
    exported-program cache describes it field by field)."""

    base: Callable = eqx.field(static=True)
    axis: str = eqx.field(static=True)
    terms: tuple[tuple, ...] = eqx.field(static=True)
    rates: bool = eqx.field(static=True)

    def __call__(self, x, u, p, c):
        ue = u[1:]
        smooth: dict = {}  # each state's smooth components, evaluated once a call
        values = []
        for _, kind, idx, _, basis in self.terms:
            if kind == "smooth":
                if (idx[0], id(basis)) not in smooth:
                    smooth[(idx[0], id(basis))] = basis(x[idx[0]], xp=jnp)
                values.append(smooth[(idx[0], id(basis))][idx[1]])
            else:
                values.append(_term(kind, idx, x, ue))
        extra = [sum((p[f"{ld}{t[0]}"] * v for t, v in zip(self.terms, values)
                      if not t[3] or ld in t[3]), 0.0 * x[0])
                 for ld in AXIS_LOADS[self.axis]]
        out = self.base(x, u[:1], p, c)
        return out + (_load_rates(self.axis, extra, c) if self.rates else jnp.stack(extra))


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


def prepared_inputs(axis: str, effects: Sequence[tuple[str, object]]) -> dict[str, str]:
    """What each input that `augment`'s `prepare` adds to a flight is (so the augmented model
    can be applied to new flights): the diagnosed constants written out."""
    ctrl, out = AXIS_INPUT[axis], {}
    for name, variant in effects:
        if name == "actuator-dynamics":
            out[f"{ctrl}_eff"] = (f"cycle-averaged {ctrl} minus its trim through a "
                                  f"{filter_text(variant)}")
        elif name == "time-offset":
            out[f"{ctrl}_eff"] = (f"cycle-averaged {ctrl} minus its trim, shifted "
                                  f"{float(variant):g} s earlier")
        elif name == "unsteady-aero" and isinstance(variant, Lagging):
            for ld in AXIS_LOADS[axis]:
                qs = " + ".join(f"{g:.4g} {x}" for x, g in variant.derivatives[ld].items())
                out[f"{ld}_lag"] = (f"the quasi-steady {ld} ({qs}, cycle-averaged states "
                                    f"less trim) through a {variant.text()}, minus itself")
        elif name == "flap-frequency":
            lag = f" through a first-order lag of {float(variant):g} s" if variant else ""
            out["f_dev"] = f"f minus its median over the flight{lag}"
            out["f_dev2"] = "f_dev squared"
        elif name == "drift":
            out["time"] = "time since the flight's first sample / 10 s"
            out["time2"] = "time squared"
    return out


def _lag_inputs(flight: Flight, axis: str, member: Lagging, cutoff: float
                ) -> dict[str, np.ndarray]:
    """`unsteady-aero`'s prepared inputs `{load}_lag`: each load's quasi-steady load (its
    derivatives on the cycle-averaged states, one decomposition of the flight) through the
    member's filter, lagging part only."""
    slow = cycle_averaged(flight, AXIS_STATES[axis], cutoff)
    return {f"{ld}_lag": lagging(quasi_steady(slow, ld, member, flight.n), flight.dt, member)
            for ld in AXIS_LOADS[axis]}


def _frequency_inputs(flight: Flight, tau: float) -> dict[str, np.ndarray]:
    """`flap-frequency`'s prepared inputs: `f` less its median (through the lag `tau`) and
    its square."""
    df = frequency_deviation(np.asarray(flight["f"], dtype=float), flight.dt, tau)
    return {"f_dev": df, "f_dev2": df ** 2}


def _smooth_terms(axis: str, member: Terms, state_index: dict):
    """`nonlinear-aero`'s terms (`_term`) for `member`: per state its smooth components in
    the simulated state, and the products of every two."""
    names = [AXIS_STATES[axis][k] for k in member.which]
    out = []
    for x in names:
        basis = member.bases.get(x)
        for k in range(member.df if basis is not None else 0):
            out.append((f"_{x}{k + 1}", "smooth", (state_index[x], k), (), basis))
    if member.products:
        for a, b in itertools.combinations(names, 2):
            out.append((f"_{a}{b}", "cross", (state_index[a], state_index[b]), (), None))
    return out


def augment(axis: str, effects: Sequence[tuple[str, object]], cutoff: float = 5.0
            ) -> tuple[GreyBoxModel, Callable[[Flight], Flight], list[str]]:
    """The `axis` model (`fwid.longitudinal`/`fwid.lateral`) with `effects` (`(name,
    variant)` pairs as the diagnosis selected them) inside its EOM.

    The acting deflection is the commanded one (`_signals.command`: as measured, less the
    flapping ripple) through the chosen filter, then split below `cutoff` Hz, as the
    diagnosis fitted the filter on the loads: a rate limit or a direction-dependent lag is
    not linear, so it must see the same signal in both places.

    **Returns:** `(model, prepare, left_out)`: `prepare(flight)` adds the columns the model
    reads (the acting deflection), `left_out` the effects that have no cycle-averaged form.
    """
    base = get_model(axis)
    loads = AXIS_LOADS[axis]
    state_index = {s: k for k, s in enumerate(base.states)}
    ctrl = AXIS_INPUT[axis]
    control = ctrl
    shift = None  # the servo (an actuator-dynamics member) or ("lead", T) of the control
    extra_inputs: list[str] = []
    terms: list[tuple] = []  # (suffix, kind, indices, loads, basis) (`Augmented`)
    left_out = []
    columns: dict[str, Callable[[Flight], np.ndarray]] = {}  # prepared extra inputs
    groups: list[Callable[[Flight], dict[str, np.ndarray]]] = []  # several made together

    def add_input(name, column, on=(), suffix=None):
        j = len(extra_inputs)
        extra_inputs.append(name)
        if column is not None:
            columns[name] = column
        terms.append((suffix or name, "input", (j,), tuple(on), None))

    for name, variant in effects:
        if name in ("actuator-dynamics", "time-offset"):
            shift = variant if name == "actuator-dynamics" else ("lead", float(variant))
            control = f"{ctrl}_eff"
        elif name == "unsteady-aero":
            if not isinstance(variant, Lagging):  # no member made for flights: no form
                left_out.append(name)
                continue
            for ld in loads:
                add_input(f"{ld}_lag", None, on=(ld,), suffix="_lag")
            groups.append(lambda fl, m=variant: _lag_inputs(fl, axis, m, cutoff))
        elif name == "flap-frequency":
            add_input("f_dev", None)
            add_input("f_dev2", None)
            groups.append(lambda fl, tau=float(variant or 0.0): _frequency_inputs(fl, tau))
        elif name == "lon-lat-coupling":
            o = other(axis)
            for s in AXIS_STATES[o] + (AXIS_INPUT[o],):
                add_input(s, None)
        elif name == "nonlinear-aero":
            if not isinstance(variant, Terms):  # no member made for flights: no form
                left_out.append(name)
                continue
            terms.extend(_smooth_terms(axis, variant, state_index))
        elif name == "drift":
            add_input("time", lambda fl: elapsed(np.asarray(fl.t, dtype=float)))
            add_input("time2", lambda fl: elapsed(np.asarray(fl.t, dtype=float)) ** 2)
        elif name == "attitude":
            k = state_index[ATTITUDE[axis]]
            terms.append((ATTITUDE[axis], "state", (k,), (), None))
        else:
            left_out.append(name)
    new = [f"{ld}{t[0]}" for t in terms for ld in loads if not t[3] or ld in t[3]]
    f = Augmented(base.f, axis, tuple(terms), rates=True)
    forces = Augmented(base.forces, axis, tuple(terms), rates=False)

    params = {k: float(v) for k, v in base.params.items()}
    params.update({k: 0.0 for k in new})
    model = GreyBoxModel(
        f, states=base.states, inputs=(control, *extra_inputs), params=params,
        free=tuple(base.free) + tuple(new), constants=base.constants, forces=forces,
        force_names=base.force_names, local=base.local,
        name=base.name + "+" + "+".join(n for n, _ in effects if n not in left_out),
    )

    def prepare(flight: Flight) -> Flight:
        new = {k: g(flight) for k, g in columns.items()}
        for g in groups:
            new.update(g(flight))
        if shift is not None and shift[0] == "lead":  # the logged column's lead (linear)
            slow = cycle_averaged(flight, (ctrl,), cutoff)[ctrl]
            new[control] = actuator_filter(slow, flight.dt, ("delay", -shift[1]))
        elif shift is not None:  # the servo on the deflection as commanded, then split
            new[control] = acting(command(flight, ctrl, cutoff), flight.dt, cutoff, shift)
        return flight.with_columns(**new) if new else flight

    return model, prepare, left_out
