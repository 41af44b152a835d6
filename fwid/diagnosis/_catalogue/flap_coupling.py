"""`flap-coupling`: the flapping loads of Eq. (12) change with the slow motion (the time
scales coupled: a linear time-periodic system's sidebands `n f +- f_manoeuvre`).

A flight's flapping series is local (its phase origin is its own), so the family modulates
the flight's own series: its harmonics `h_k` and their phase derivatives `h_k'` (a shift of
the harmonic), multiplied by functions of the cycle-averaged states and controls, with
global coefficients. Members (`MODULATIONS`, chosen by leave-one-flight-out error on the
fitting flights):

- the whole series modulated linearly by every state and control of both axes (`x h`,
  `x h'`);
- each harmonic on its own, modulated by the manoeuvred axis's states and control, linearly
  or by smooth functions of them as well (`_smooth.py`'s first component: an even bend
  beside the odd linear term);
- the whole series modulated by the manoeuvred axis's variables, linearly and smoothly.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._signals import Signals
from ._effect import Effect, axis_of, slow_of, variables
from .nonlinear_aero import smooth_bases


@dataclasses.dataclass(frozen=True)
class Modulation:
    """A member: `per_harmonic` (each harmonic its own coefficients, or the whole series
    one), `both_axes` (every state and control, or the manoeuvred axis's), `smooth` (the
    smooth bend of each variable too). `axis` and `bases` (the manoeuvred axis and its
    variables' smooth bases) are the fitting flights' (`bind`), not part of its identity."""

    per_harmonic: bool
    both_axes: bool
    smooth: bool
    axis: str = dataclasses.field(default="lon", compare=False, hash=False)
    bases: dict = dataclasses.field(default_factory=dict, compare=False, hash=False,
                                    repr=False)

    def to_json(self) -> dict:
        return {"per_harmonic": self.per_harmonic, "both_axes": self.both_axes,
                "smooth": self.smooth}

    def text(self, axis: str = "lon") -> str:
        what = "each harmonic" if self.per_harmonic else "the flapping series"
        by = "every state and control" if self.both_axes else "the manoeuvred axis's states and control"
        return f"{what} modulated by {by}" + (", linearly and smoothly" if self.smooth
                                                else ", linearly")


#: The members, the largest first (`Engine.choose` weighs them by their size).
MODULATIONS = (Modulation(True, False, True), Modulation(False, True, False),
               Modulation(True, False, False), Modulation(False, False, True))


def _columns(s: Signals, load, m: Modulation, h, dh):
    names = variables("lon") + variables("lat") if m.both_axes else variables(m.axis)
    mods = []
    for x in names:
        v = slow_of(s, x)
        mods.append(v[:, None])
        if m.smooth and m.bases.get(x) is not None:
            mods.append(m.bases[x].at(v)[:, :1])
    g = np.concatenate(mods, axis=1)  # (n, functions)
    if m.per_harmonic:
        carriers = np.concatenate([h, dh], axis=1)  # (n, 2 harmonics)
    else:
        carriers = np.stack([h.sum(axis=1), dh.sum(axis=1)], axis=1)
    return (carriers[:, :, None] * g[:, None, :]).reshape(s.n, -1)


def _bind(effect: Effect, engine, idx) -> Effect:
    """The members for the manoeuvred axis, with its variables' smooth bases over the
    fitting flights (`nonlinear-aero`'s)."""
    axis = axis_of(engine.own[0]) if engine.own else "lon"
    bases = smooth_bases(engine, idx)
    return dataclasses.replace(effect, variants=tuple(
        dataclasses.replace(v, axis=axis, bases=bases) for v in effect.variants))


EFFECT = Effect(
    "flap-coupling",
    "flapping loads modulated by the body motion and inputs (time scales coupled), the "
    "whole series or each harmonic",
    "flapping",
    _columns,
    MODULATIONS,
    crosses_axes=True,
    sized=True,
    bind=_bind,
)
