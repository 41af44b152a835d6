"""The diagnosed effects inside the equations of motion: the grey-box model of Eqs. (7-8)
augmented, so that the output-error estimator (Eqs. 10-11) can re-fit it and the gap can be
measured where a user sees it, in the simulated states.

Each effect of the verdict becomes terms of the cycle-averaged model:

- `actuator-dynamics` and `time-offset`: the acting deflection, the cycle-averaged measured
  one through the diagnosed filter (a lead for `time-offset`), replaces it as the model's
  input (`d_eff`, a prepared column; the filter is the diagnosis's, the control derivative
  is re-estimated);
- `unsteady-aero`: the lagging part `lag(x) - x` of the axis's measured states (the
  diagnosed time constant; prepared columns `u_lag`, ...) as extra inputs, with a derivative
  per own load (`Mw_lag`, ...: Eqs. 1-6 with a lagging share);
- `flap-frequency`: the measured flapping frequency's deviation from its median, and its
  square, as extra inputs with a derivative per own load (`Xf`, `Xff`, ...); the frequency
  lag, when one was diagnosed, is applied to the prepared column;
- `lon-lat-coupling`: the other axis's measured states and control as extra inputs, with a
  derivative per own load (`Xv`, `Mdr`, `Lq`, ...: Eqs. 1-6 with the cross terms);
- `nonlinear-aero`: the quadratic terms of `_catalogue.py` in the *simulated* states, with a
  coefficient per own load (`M_qq`, `Z_w|w|`, `X_uw`, ...);
- the probe `attitude`: a derivative of each own load on the attitude state (`Mtheta`);
- the probe `drift`: the time since the flight's start (per 10 s) and its square as extra
  inputs, with a coefficient per own load (`Xtime`, `Xtime2`, ...), as the probe fits them.

The extra loads enter the EOM exactly as the aerodynamic ones do (divided by the mass, or
through the inertia matrix), and the force model used for the least-squares start carries
them too. `flap-coupling` acts on the flapping part, which the cycle-averaged simulation
does not contain: it is left out (the result says so).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..data import Flight
from ..decomposition import decompose
from ..identification import get_model
from ..models import GreyBoxModel
from ._catalogue import actuator_filter, filter_text, frequency_deviation, lagging_part
from ._probes import ATTITUDE, elapsed
from ._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, other

#: Effects (catalogue and probes) that have a form inside the cycle-averaged EOM.
IN_EOM = ("actuator-dynamics", "time-offset", "unsteady-aero", "flap-frequency",
          "lon-lat-coupling", "nonlinear-aero", "attitude", "drift")


def _quadratic_terms(axis: str, state_index: dict[str, int]) -> list[tuple[str, str, tuple]]:
    """`nonlinear-aero`'s terms as `(suffix, kind, state indices)` (see `_term`), in
    `_catalogue.quadratic_names` order."""
    xs = [state_index[s] for s in AXIS_STATES[axis]]
    names = AXIS_STATES[axis]
    out = []
    for i, a in enumerate(names):
        out.append((f"_{a}{a}", "square", (xs[i],)))
        out.append((f"_{a}|{a}|", "abs", (xs[i],)))
    for i in range(len(xs)):
        for j in range(i + 1, len(xs)):
            out.append((f"_{names[i]}{names[j]}", "cross", (xs[i], xs[j])))
    return out


def _term(kind: str, idx: tuple, x, ue):
    """One extra-load term: the extra input `ue[idx[0]]` (`"input"`), the state `x[idx[0]]`
    (`"state"`), its square, `x |x|` (`"abs"`) or the product `x[i] x[j]` (`"cross"`)."""
    if kind == "input":
        return ue[idx[0]]
    if kind == "state":
        return x[idx[0]]
    if kind == "square":
        return x[idx[0]] * x[idx[0]]
    if kind == "abs":
        return x[idx[0]] * jnp.abs(x[idx[0]])
    return x[idx[0]] * x[idx[1]]


class Augmented(eqx.Module):
    """The augmented model's state equation (`rates=True`: Eqs. 7-8 with the extra loads
    entering as the aerodynamic ones do) or its loads (`rates=False`): `base(x, u[:1], p, c)`
    plus, on each of the axis's loads `ld`, the sum over `terms` (`(suffix, kind, indices)`,
    see `_term`) of `p[ld + suffix]` times the term, the extra inputs being `u[1:]`.

    A module of static fields rather than a closure, so that the estimator's program for the
    augmented model is kept across processes like the baseline's (`fwid.estimate`'s
    exported-program cache describes it field by field)."""

    base: Callable = eqx.field(static=True)
    axis: str = eqx.field(static=True)
    terms: tuple[tuple[str, str, tuple[int, ...]], ...] = eqx.field(static=True)
    rates: bool = eqx.field(static=True)

    def __call__(self, x, u, p, c):
        ue = u[1:]
        extra = [sum((p[f"{ld}{suffix}"] * _term(kind, idx, x, ue)
                      for suffix, kind, idx in self.terms), 0.0 * x[0])
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
        elif name == "unsteady-aero":
            for s in AXIS_STATES[axis]:
                out[f"{s}_lag"] = (f"lag({s}) - {s}: {s} through a first-order lag of tau = "
                                   f"{float(variant):g} s, minus {s}")
        elif name == "flap-frequency":
            lag = f" through a first-order lag of {float(variant):g} s" if variant else ""
            out["f_dev"] = f"f minus its median over the flight{lag}"
            out["f_dev2"] = "f_dev squared"
        elif name == "drift":
            out["time"] = "time since the flight's first sample / 10 s"
            out["time2"] = "time squared"
    return out


def augment(axis: str, effects: Sequence[tuple[str, object]], cutoff: float = 5.0
            ) -> tuple[GreyBoxModel, Callable[[Flight], Flight], list[str]]:
    """The `axis` model (`fwid.longitudinal`/`fwid.lateral`) with `effects` (`(name,
    variant)` pairs as the diagnosis selected them) inside its EOM.

    The acting deflection is the cycle-averaged measured one (below `cutoff` Hz, as the
    diagnosis fitted the filter on the loads) through the chosen filter: a rate limit or a
    direction-dependent lag is not linear, so it must see the same signal in both places
    (the flapping ripple of the raw column would saturate a rate limit that the
    cycle-averaged deflection never reaches).

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
    terms: list[tuple[str, str, tuple]] = []  # (suffix, kind, indices) per own load (`_term`)
    left_out = []
    columns: dict[str, Callable[[Flight], np.ndarray]] = {}  # prepared extra inputs

    def add_input(name, column):
        j = len(extra_inputs)
        extra_inputs.append(name)
        if column is not None:
            columns[name] = column
        terms.append((name, "input", (j,)))

    for name, variant in effects:
        if name in ("actuator-dynamics", "time-offset"):
            shift = variant if name == "actuator-dynamics" else ("delay", -float(variant))
            control = f"{ctrl}_eff"
        elif name == "unsteady-aero":
            for s in AXIS_STATES[axis]:
                add_input(f"{s}_lag", lambda fl, s=s, tau=float(variant): lagging_part(
                    np.asarray(fl[s], dtype=float), fl.dt, tau))
        elif name == "flap-frequency":
            tau = float(variant or 0.0)
            add_input("f_dev", lambda fl, tau=tau: frequency_deviation(
                np.asarray(fl["f"], dtype=float), fl.dt, tau))
            add_input("f_dev2", lambda fl, tau=tau: frequency_deviation(
                np.asarray(fl["f"], dtype=float), fl.dt, tau) ** 2)
        elif name == "lon-lat-coupling":
            o = other(axis)
            for s in AXIS_STATES[o] + (AXIS_INPUT[o],):
                add_input(s, None)
        elif name == "nonlinear-aero":
            chosen = _quadratic_terms(axis, state_index)
            if variant is not None:  # a subset of the terms (`_catalogue.QUADRATIC_SUBSETS`)
                chosen = [chosen[k] for k in variant]
            terms.extend(chosen)
        elif name == "drift":
            add_input("time", lambda fl: elapsed(np.asarray(fl.t, dtype=float)))
            add_input("time2", lambda fl: elapsed(np.asarray(fl.t, dtype=float)) ** 2)
        elif name == "attitude":
            k = state_index[ATTITUDE[axis]]
            terms.append((ATTITUDE[axis], "state", (k,)))
        else:
            left_out.append(name)
    new = [f"{ld}{suffix}" for suffix, _, _ in terms for ld in loads]
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
        if shift is not None:
            d = np.asarray(flight[ctrl]) - float(flight.trim_value(ctrl))
            slow = np.asarray(decompose({ctrl: d}, flight.dt, split_cutoff=cutoff).averaged[ctrl])
            new[control] = actuator_filter(slow, flight.dt, shift)
        return flight.with_columns(**new) if new else flight

    return model, prepare, left_out
