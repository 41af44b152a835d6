"""Does the control follow the states? A test for closed-loop flights.

Output error simulates the model from the measured control alone. When an autopilot (or a
pilot) moved the control in answer to the states, the control carries the disturbances the
states felt, the simulation does not, and the output-error estimates are biased; filter
error (a Kalman filter that follows the measured states) and multiple shooting (the
simulation restarted from them) are not.

The test is Granger's: does the states' past predict the control beyond what the control's
own past predicts? Both are low-passed at the cycle-averaged cutoff by a causal filter (a
zero-phase one would let the states' samples see the control's future) and sampled at half
a period of the cutoff. The control is regressed on its own last [`CONTROL_LAGS`][] samples,
then also on the states' last [`STATE_LAGS`][]; `explained` is the share of the first
regression's residual variance that the states remove, and an F test with one degree of
freedom per half period (the samples between are not independent) says whether that share
is more than chance. In open loop the states' past is the control's past filtered by the
vehicle, which the control's own lags already hold.

Measured (cutoff 5 Hz): fwid's simulated open-loop flights (4.5 s and 30 s, 3211 inputs,
with and without turbulence, both axes) explained 0.02-0.33, those with p below 1e-3 at most
0.17; two real Flapper Drone flights under their autopilot 0.42 and 0.52 at p 1e-54 and
2e-5. What it cannot see: a noise-free controller that feeds back only what the control's
own past already reconstructs (a static gain on a state the control alone makes observable).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import signal, stats

from ..data._flight import Flight
from .._advice import advise

#: The recorded controls tested: an input a model derives from them (the diagnosis's filtered
#: deflection `de_eff`, say) follows the states through the recorded one by construction.
RECORDED_CONTROLS = ("de", "dr")
#: The control's own past in the restricted regression, in half periods of the cutoff.
CONTROL_LAGS = 4
#: The states' past added in the full regression.
STATE_LAGS = 2
#: A flight is closed loop when the states explain at least this share ...
EXPLAINED_MIN = 0.25
#: ... with an F test below this p value.
P_MAX = 1e-3


@dataclass(frozen=True)
class ClosedLoop:
    """The closed-loop test of one control on one flight: the share of the control's own
    unpredictable variance the states' past explains (`explained`), its F test's `p_value`,
    and whether the flight counts as `closed` loop."""

    flight: str
    control: str
    explained: float
    p_value: float
    closed: bool

    def to_json(self) -> dict:
        return {"control": self.control, "explained": self.explained,
                "p_value": self.p_value, "closed": self.closed}


def closed_loop_test(flight: Flight, control: str, states: Sequence[str],
                     cutoff: float = 5.0) -> ClosedLoop | None:
    """[`ClosedLoop`][] for `control` against `states` of `flight` (`None` when the flight
    lacks a column, is too short for the regressions, or `control` is not a recorded one)."""
    if control not in RECORDED_CONTROLS or control not in flight or not all(s in flight for s in states):
        return None
    t = np.asarray(flight["t"], dtype=float)
    dt = float(t[1] - t[0])
    if not 0 < cutoff < 0.5 / dt:
        return None
    b, a = signal.butter(2, cutoff, fs=1.0 / dt)

    def low(col):
        v = np.asarray(flight[col], dtype=float)
        return signal.lfilter(b, a, v - v[0])

    u = low(control)
    x = np.column_stack([low(s) for s in states])
    step = max(1, round(0.5 / (cutoff * dt)))
    rows = np.arange(CONTROL_LAGS * step, len(u))
    restricted = np.column_stack([np.ones(len(rows))]
                                 + [u[rows - k * step] for k in range(1, CONTROL_LAGS + 1)])
    full = np.column_stack([restricted]
                           + [x[rows - k * step] for k in range(1, STATE_LAGS + 1)])
    n_eff = len(rows) / step
    dof = n_eff - full.shape[1]
    if dof < 5 or np.ptp(u) == 0:
        return None
    y = u[rows]

    def rss(A):
        return float(np.sum((y - A @ np.linalg.lstsq(A, y, rcond=None)[0]) ** 2))

    r0, r1 = rss(restricted), rss(full)
    if not r0 > 0:
        return None
    k = full.shape[1] - restricted.shape[1]
    explained = max(0.0, 1.0 - r1 / r0)
    p = float(stats.f.sf((r0 - r1) / k / max(r1 / dof, 1e-300), k, dof))
    return ClosedLoop(flight.name, control, explained, p,
                      explained >= EXPLAINED_MIN and p < P_MAX)


def closed_loop_warning(tests: Sequence[ClosedLoop | None], model_name: str) -> str | None:
    """The warning for the flights whose control follows the states (`None` if none)."""
    closed = [c for c in tests if c is not None and c.closed]
    if not closed:
        return None
    which = ", ".join(f"{c.flight} ({c.control}: {100 * c.explained:.0f} %)" for c in closed)
    return (f"{which}: the control follows the states (closed loop: the states' past "
            "explains that share of the control beyond its own past); output error is "
            f"biased there, as the control carries the disturbances the simulation does not "
            f"see; fit the {model_name} model with a method that is not: "
            f"{advise('closed-loop', 'output-error')}")
