"""The catalogue of unmodelled effects (the effect names) as augmentations of the model.

Each `Effect` adds a group of regressors to the cycle-averaged linear load model of Eqs. (2-6)
(`base_columns`), or to the flapping series of Eq. (12), shared by all flights. Each is a
family of its physics, one module a family, so that a new family is one new file:

- `flap_coupling`: the flapping series, or each harmonic, modulated by the slow motion;
- `nonlinear_aero`: smooth functions (penalised splines) of the states and control, and
  their products;
- `lon_lat_coupling`: the other axis's states and control;
- `actuator_dynamics`: the measured deflection through a servo, linear or not;
- `unsteady_aero`: the quasi-steady load through a causal filter, lagging part only;
- `time_offset`: the logged deflection shifted earlier;
- `flap_frequency`: the flapping frequency's slow deviation.

A family's members are its `variants`; one whose members differ in size or form is `sized`:
its member is chosen inside the fitting flights by leave-one-flight-out error, so that no
family wins by being bigger. None of them is tuned to a particular simulator.
"""

from __future__ import annotations

from . import (actuator_dynamics, flap_coupling, flap_frequency, lon_lat_coupling,
               nonlinear_aero, time_offset, unsteady_aero)
from ._effect import Effect as Effect
from ._effect import axis_of as axis_of
from ._effect import base_columns as base_columns
from ._effect import slow_of as slow_of
from ._filters import lagged as lagged
from .actuator_dynamics import ACTUATOR_FILTERS as ACTUATOR_FILTERS
from .actuator_dynamics import acting as acting
from .actuator_dynamics import actuator_filter as actuator_filter
from .actuator_dynamics import filter_text as filter_text
from .flap_frequency import frequency_deviation as frequency_deviation

#: The candidate effects that `fwid.diagnose` tries, in this order; their names are the
#: effect names of `diagnosis.json` and of `fwid simulate --effect`.
CATALOGUE: tuple[Effect, ...] = tuple(m.EFFECT for m in (
    flap_coupling, nonlinear_aero, lon_lat_coupling, actuator_dynamics, unsteady_aero,
    time_offset, flap_frequency))

#: Effect names the diagnosis can return (with "none").
EFFECT_NAMES = tuple(e.name for e in CATALOGUE)


def member_json(variant):
    """A family's member (an effect's variant) as `diagnosis.json` holds it (`member`): every
    number it needs to be formed again on new flights (a filter's parameters, a spline's
    pieces, a quasi-steady load's derivatives)."""
    if variant is None or isinstance(variant, (int, float, str)):
        return variant
    if isinstance(variant, tuple):
        return list(variant)
    return variant.to_json()


def member_from_json(name: str, d):
    """The member of effect `name` back from `member_json`."""
    if d is None or isinstance(d, (int, float, str)):
        return d
    if isinstance(d, list):
        return tuple(d)
    kinds = {"nonlinear-aero": nonlinear_aero.Terms, "unsteady-aero": unsteady_aero.Lagging}
    if name not in kinds:
        raise ValueError(f"{name}'s member {d!r} has no form outside the diagnosis")
    return kinds[name].from_json(d)


def get_effect(name: str) -> Effect:
    for e in CATALOGUE:
        if e.name == name:
            return e
    raise ValueError(f"unknown effect {name!r}; choose from {', '.join(EFFECT_NAMES)}")
