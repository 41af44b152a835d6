"""One candidate effect of the catalogue, and the signals every family reads."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from .._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, Signals

#: The states each load is reconstructed from (their rates are in it, Section III).
OWN_STATES = {"X": ("u",), "Z": ("w",), "M": ("q",), "Y": ("v",), "L": ("p", "r"),
              "N": ("p", "r")}


def axis_of(load: str) -> str:
    return "lon" if load in AXIS_LOADS["lon"] else "lat"


def slow_of(s: Signals, name: str) -> np.ndarray:
    """The cycle-averaged perturbation `name` of `s` (zeros when the flight lacks it)."""
    return s.slow.get(name, np.zeros(s.n))


def variables(axis: str) -> tuple[str, ...]:
    """The cycle-averaged states and control of `axis` (Eqs. 2 and 5)."""
    return AXIS_STATES[axis] + (AXIS_INPUT[axis],)


def base_columns(s: Signals, load: str, band: str) -> np.ndarray:
    """Global regressors of the baseline model of `load` in `band`: the states and control
    of its axis (Eqs. 2 and 5), cycle-averaged below the split; above it, their parts above the
    split (what a step input puts there; the flapping series itself, Eq. 12, is local)."""
    src = s.slow if band == "averaged" else s.fast
    return np.stack([src.get(x, np.zeros(s.n)) for x in variables(axis_of(load))], axis=1)


@dataclasses.dataclass(frozen=True)
class Effect:
    """One candidate effect: `columns(signals, load, variant, h, dh)` returns the regressors
    it adds to the model of `load` in `band` (`h`, `dh`: the flight's flapping series of that
    load and its phase derivative); `variants` are the discrete choices fitted by trying each
    (e.g. time constants). With `replaces_input`, the single column returned replaces the
    control column of the baseline instead of being added. `labels(load)`, if given, names
    the measured signal behind each column (the drivers of an unexplained gap).

    `bind(effect, engine, idx)`, if given, returns the effect made for the fitting flights
    `idx` of the least-squares `engine` (the spline bases of a smooth family spanning their
    range, the quasi-steady load of their baseline): the diagnosis binds every entry once,
    before any is fitted, so that all folds share one family."""

    name: str
    description: str
    band: str
    columns: Callable = dataclasses.field(repr=False)
    variants: tuple = (None,)
    replaces_input: bool = False
    labels: Callable | None = dataclasses.field(default=None, repr=False, compare=False)
    #: A rival outside the catalogue (`_probes.py`): when it wins, the verdict is
    #: `unexplained`.
    probe: bool = False
    #: May it act on the loads of the axis that was not manoeuvred? Only when its columns
    #: there carry the manoeuvred axis's signals (the coupling, the flapping modulated by
    #: every state) or belong to neither axis (the flapping frequency, time). Built from the
    #: other axis's own states, attitude or control, which hardly move, its columns there
    #: would only fit what their noise hides from the baseline (`Engine.allowed`).
    crosses_axes: bool = False
    #: Is it a family whose members differ in size or form (subsets of a family of columns,
    #: filters of several kinds)? Then the member is chosen by leave-one-flight-out error on
    #: the fitting flights, not by training error, which prefers the largest or most
    #: flexible (`Engine.best_variant`).
    sized: bool = False
    #: Are its columns dynamic functions of the measured states (causal filters of them)? A
    #: disturbance drives the states, so such columns predict part of what it does to the
    #: loads; the diagnosis takes the entry as an explanation only when it whitens the
    #: residual (`_disturbance.whitens`), as it does a probe.
    filters_states: bool = False
    bind: Callable | None = dataclasses.field(default=None, repr=False, compare=False)
    #: `refine(member)`: members near a chosen one, tried after it (one of its numbers on a
    #: finer grid), for a `sized` family whose grid is a product too large to try whole.
    refine: Callable | None = dataclasses.field(default=None, repr=False, compare=False)
    #: `all_columns(signals, load, variants)`: the column of each member at once, `(n,
    #: len(variants))`, for a family that `replaces_input` whose members are cheaper made
    #: together (a servo's outputs split in one call: `Engine.design` asks for all members of
    #: a flight the first time it needs one).
    all_columns: Callable | None = dataclasses.field(default=None, repr=False, compare=False)

    def bound(self, engine, idx) -> Effect:
        """The effect made for the fitting units `idx` of `engine` (`bind`), or itself."""
        return self.bind(self, engine, idx) if self.bind is not None else self
