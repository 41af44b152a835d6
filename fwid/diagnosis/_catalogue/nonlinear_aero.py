"""`nonlinear-aero`: cycle-averaged loads that are smooth, not linear, functions of the states
of their axis (the terms beyond Eq. 2's first order: a bend, a saturation, a one-sided
stall, quadratic drag).

The family is additive: per state of the axis, `df` smooth components
beyond the linear one (`_smooth.py`: a P-spline reduced to its smoothest `df` dimensions,
even and odd shapes both in its span), and, as the low-order interactions of two
states, their products. The control's own nonlinearity (a saturation, a dead band) is
`actuator-dynamics`' domain, as its filter is: a static nonlinearity of the deflection acting
through the control derivative is what a servo does, and a family of the control here would
take that effect's place. Its members (`TERMS`) range from one state's bend to every
state's finest shapes with the products; the member, and so the effective degrees of
freedom, is chosen by leave-one-flight-out error on the fitting flights (`Effect.sized`),
never by a simulator's form.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from .._signals import Signals
from .._signals import AXIS_STATES
from ._effect import Effect, axis_of, slow_of, variables
from ._smooth import MAX_DF, Smooth, smooth_basis


@dataclasses.dataclass(frozen=True)
class Terms:
    """A member of the family: the smooth components `df` of the variables `which` (indices
    into the axis's states), with the products of every two of them when `products`;
    `bases` (by variable name) are the fitting flights' (`bind`), not part of its identity."""

    which: tuple[int, ...]
    df: int
    products: bool = False
    bases: dict = dataclasses.field(default_factory=dict, compare=False, hash=False,
                                    repr=False)

    def to_json(self) -> dict:
        return {"which": list(self.which), "df": self.df, "products": self.products,
                "bases": {x: b.to_json() for x, b in self.bases.items() if b is not None}}

    @classmethod
    def from_json(cls, d: dict) -> Terms:
        return cls(tuple(d["which"]), int(d["df"]), bool(d["products"]),
                   {x: Smooth.from_json(b) for x, b in d.get("bases", {}).items()})

    def text(self, axis: str) -> str:
        names = [AXIS_STATES[axis][k] for k in self.which]
        out = (f"smooth in {', '.join(names)} ({self.df} degree{'s' * (self.df > 1)} of "
               f"freedom each)") if self.df else ""
        if self.products:
            out += (" and " if out else "") + "products of " + ", ".join(names)
        return out


ALL = (0, 1, 2)
#: The members, the whole family first: every state at each size, with and without their
#: products; each state alone (`Engine.choose` weighs them by their size).
TERMS = ((Terms(ALL, MAX_DF, True),)
         + tuple(Terms(ALL, df) for df in (1, 2, MAX_DF))
         + (Terms(ALL, 0, True), Terms(ALL, 2, True))
         + tuple(Terms((k,), df) for k in ALL for df in (1, 2, MAX_DF)))


def columns_of(slow: dict, axis: str, terms: Terms) -> np.ndarray:
    """The member's columns from the cycle-averaged perturbations `slow` (by name)."""
    names = AXIS_STATES[axis]
    n = len(next(iter(slow.values())))
    cols = []
    for k in terms.which:
        basis: Smooth | None = terms.bases.get(names[k])
        if terms.df and basis is not None:
            x = slow.get(names[k])
            cols.append((basis(np.zeros(n)) if x is None else basis.at(x))[:, :terms.df])
    if terms.products:
        for a, b in itertools.combinations(terms.which, 2):
            cols.append((slow.get(names[a], np.zeros(n)) * slow.get(names[b], np.zeros(n)))
                        [:, None])
    return np.concatenate(cols, axis=1) if cols else np.zeros((n, 0))


def _columns(s: Signals, load, terms: Terms, h, dh):
    axis = axis_of(load)
    return columns_of({x: slow_of(s, x) for x in AXIS_STATES[axis]}, axis, terms)


def smooth_bases(engine, idx) -> dict[str, Smooth | None]:
    """Each state's and control's smooth basis over the range of the units `idx` of
    `engine` (both axes' that the flights hold), made once per engine and units
    (`Engine.made`)."""
    def make():
        bases = {}
        for x in variables("lon") + variables("lat"):
            pooled = [engine.units[i].signals.slow[x] for i in idx
                      if x in engine.units[i].signals.slow]
            if pooled:
                bases[x] = smooth_basis(np.concatenate(pooled))
        return bases

    return engine.made(("smooth_bases", tuple(idx)), make)


def _bind(effect: Effect, engine, idx) -> Effect:
    """The family with each variable's smooth basis over the fitting flights' range."""
    bases = smooth_bases(engine, idx)
    return dataclasses.replace(effect, variants=tuple(
        dataclasses.replace(v, bases=bases) for v in effect.variants))


EFFECT = Effect(
    "nonlinear-aero",
    "cycle-averaged loads smooth (not linear) functions of the states: penalised splines "
    "of each and their products",
    "averaged",
    _columns,
    TERMS,
    sized=True,
    bind=_bind,
)
