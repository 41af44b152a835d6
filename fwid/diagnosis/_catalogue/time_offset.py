"""`time-offset`: the logged deflection is late against the states (a clock offset between
the logs; `actuator-dynamics` covers the deflection acting *after* it is logged, which a time
offset of the other sign cannot be told from): the deflection shifted earlier by a lead from
`LEADS` replaces the measured one, like `actuator-dynamics`."""

from __future__ import annotations

from .._signals import AXIS_INPUT, Signals
from ._effect import Effect, axis_of, slow_of
from ._filters import lagged
from .actuator_dynamics import SHORT

#: Leads [s] tried, the shortest (`SHORT`) those of `actuator-dynamics`' delays: a late log
#: and a late servo are one net shift of opposite sign. A lead the grid misses by much
#: leaves a remainder of the step response that a second family takes up (`unsteady-aero`'s
#: delay): a 6 ms offset, with 10 ms the shortest lead, read as `unsteady-aero` beside
#: `time-offset`.
LEADS = SHORT + (0.01, 0.02, 0.03, 0.05, 0.07, 0.1)


def _columns(s: Signals, load, lead, h, dh):
    return lagged(slow_of(s, AXIS_INPUT[axis_of(load)]), s.dt, "delay", -lead)[:, None]


EFFECT = Effect(
    "time-offset",
    "the logged deflection is late against the states (the response leads it)",
    "averaged",
    _columns,
    LEADS,
    replaces_input=True,
    labels=lambda load: (AXIS_INPUT[axis_of(load)],),
)
