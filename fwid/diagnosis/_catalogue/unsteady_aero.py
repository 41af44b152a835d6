"""`unsteady-aero`: the load lags the load it would have in steady flow (a lagging wake:
Wagner's indicial lift, Kuessner's gust response).

The quasi-steady load is the baseline's own: Eqs. (2-6) with the derivatives fitted to the
fitting flights (`bind`), without the control term (the deflection through a filter is
`actuator-dynamics`) and without the load's own state (`OWN_STATES`: a load is reconstructed
from that state's rate, Section III, so its lag would fit the load's own noise). The
entry's one column per load is that quasi-steady load through a causal filter, lagging part
only (filtered minus unfiltered: the quasi-steady part itself is in the baseline), with one
free coefficient per load: the capacity of `actuator-dynamics`, one filtered column.

Filters (`FILTERS`, the member chosen by leave-one-flight-out error on the fitting flights):
a first-order lag `tau`, a two-pole indicial form (Jones's approximation of Wagner's
function, `0.165 exp(-0.0455 s) + 0.335 exp(-0.3 s)`: two lags of time constants `tau`
and `6.6 tau` sharing the lag in those proportions), and a short pure delay.

A member whose time is shorter than the cycle-averaged band's shortest time scale,
`1 / (2 pi f_split)` (32 ms at the 5 Hz split), is no lag the band can show: on every
frequency below the split its lagging part is `-tau` times the rate of the quasi-steady load
(within `omega tau < 1`), and the states' rates carry the axis's other loads through the
equations of motion (`w' = Z / m + ...`), so such a column would fit any other load's misfit
or a gust's load. The family holds only the members the band resolves (`bind`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._signals import AXIS_STATES, Signals
from ._effect import OWN_STATES, Effect, axis_of, slow_of
from ._filters import lagged

#: Time constants / delays [s] of the members.
LAGS = (0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.14, 0.2)
INDICIAL = (0.01, 0.02, 0.03, 0.05, 0.07)
DELAYS = (0.01, 0.02, 0.03, 0.05)
#: Jones's two-pole approximation of Wagner's function: the shares of the lag and the
#: ratio of the second time constant to the first.
WAGNER_SHARES = (0.335 / 0.5, 0.165 / 0.5)
WAGNER_RATIO = 0.3 / 0.0455


@dataclasses.dataclass(frozen=True)
class Lagging:
    """A member: the filter `kind` (`"lag"`, `"indicial"`, `"delay"`) of time `tau` [s];
    `derivatives` (by load, by state) the fitting flights' quasi-steady load (`bind`), not
    part of its identity."""

    kind: str
    tau: float
    derivatives: dict = dataclasses.field(default_factory=dict, compare=False, hash=False,
                                          repr=False)

    def to_json(self) -> dict:
        return {"kind": self.kind, "tau": self.tau, "derivatives": self.derivatives}

    @classmethod
    def from_json(cls, d: dict) -> Lagging:
        return cls(d["kind"], float(d["tau"]), {ld: {x: float(g) for x, g in gs.items()}
                                                for ld, gs in d.get("derivatives", {}).items()})

    def text(self, axis: str = "lon") -> str:
        return {"lag": f"first-order lag, tau = {self.tau:g} s",
                "indicial": f"two-pole indicial (Wagner) lag, tau = {self.tau:g} and "
                            f"{WAGNER_RATIO * self.tau:.2g} s",
                "delay": f"delay {self.tau:g} s"}[self.kind]


FILTERS = (tuple(Lagging("lag", t) for t in LAGS)
           + tuple(Lagging("indicial", t) for t in INDICIAL)
           + tuple(Lagging("delay", t) for t in DELAYS))


def unsteady_states(load: str) -> tuple[str, ...]:
    """The states whose quasi-steady load `unsteady-aero` lags for `load` (not its own)."""
    return tuple(x for x in AXIS_STATES[axis_of(load)] if x not in OWN_STATES[load])


def lagging(x: np.ndarray, dt: float, member: Lagging) -> np.ndarray:
    """What the member's filter holds back of `x`: filtered minus `x`."""
    if member.kind == "indicial":
        a, b = WAGNER_SHARES
        return (a * lagged(x, dt, "lag", member.tau)
                + b * lagged(x, dt, "lag", WAGNER_RATIO * member.tau) - x)
    return lagged(x, dt, member.kind, member.tau) - x


def quasi_steady(slow: dict, load: str, member: Lagging, n: int) -> np.ndarray:
    """`load`'s quasi-steady part in the states (module docstring) from `slow` (by name)."""
    gains = member.derivatives.get(load, {})
    return sum((g * slow.get(x, np.zeros(n)) for x, g in gains.items()), np.zeros(n))


def _columns(s: Signals, load, member: Lagging, h, dh):
    slow = {x: slow_of(s, x) for x in unsteady_states(load)}
    return lagging(quasi_steady(slow, load, member, s.n), s.dt, member)[:, None]


def resolved(member: Lagging, cutoff: float) -> bool:
    """Does the cycle-averaged band below `cutoff` [Hz] show `member` as a lag, not a rate
    (module docstring)? Its shortest time (the indicial form's first lag) reaches the band's
    shortest time scale."""
    return member.tau >= 1.0 / (2.0 * np.pi * cutoff)


def _bind(effect: Effect, engine, idx) -> Effect:
    """The members the band resolves (`resolved`, at the engine's split), with the
    baseline's derivatives fitted on the fitting units `idx`."""
    derivatives = {}
    for load in engine.loads:
        theta, _ = engine.fit(idx, (load, "averaged"), ())
        states = AXIS_STATES[axis_of(load)]
        derivatives[load] = {x: float(theta[states.index(x)]) for x in unsteady_states(load)}
    return dataclasses.replace(effect, variants=tuple(
        dataclasses.replace(v, derivatives=derivatives) for v in effect.variants
        if resolved(v, engine.cutoff)))


EFFECT = Effect(
    "unsteady-aero",
    "the loads lag their quasi-steady values (a lagging wake): the baseline's state load "
    "through a causal filter",
    "averaged",
    _columns,
    FILTERS,
    labels=lambda load: (load,),
    sized=True,
    filters_states=True,
    bind=_bind,
)
