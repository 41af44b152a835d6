"""`actuator-dynamics`: the deflection that acts is the commanded one through a servo.

`d_eff` replaces `d` in the load's own model (no new coefficient: the control derivative acts
on `d_eff`), one column only, so it cannot soak up unrelated misfit. The family
(`ACTUATOR_FILTERS`) holds the linear servos (a first-order lag, a pure delay, both, a
second-order servo) and the classical servo nonlinearities, each of one to three numbers
from a grid: a rate limit, a direction-dependent lag, and, before or after a first-order
lag (Hammerstein and Wiener forms), a saturation, a dead band and a backlash (play in the
linkage, the one with memory). The servo acts on the deflection as commanded: the measured
one less its flapping ripple (`Signals.commanded`), which the wings, not the servo, impose.
The nonlinearities' sizes are fractions of the fitting flights' largest commanded
deflection, the rate limits the times to cross it (`bind`): a limit only shows where the
flights reach it, whatever the surface, its units, the manoeuvre's size or the sample rate.
The member is chosen by leave-one-flight-out error on the fitting flights, as
`nonlinear-aero`'s size; a nonlinear or rate-limited member's lag is then refined on `LAGS`
up to 0.1 s (`refine`). The grids are generic (servo bandwidths of a few to tens of Hz;
limits, play and rate limits relative to what the flights reach), not a simulator's
values.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._signals import AXIS_INPUT, Signals, averaged
from ._effect import Effect, axis_of
from ._filters import backlash, lagged, second_order, stepped

#: Time constants / delays [s] of the first-order members.
LAGS = (0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.14, 0.2)
#: The lag and delay members' shortest times (below `LAGS`, down to half a sample at 200
#: Hz), also `time-offset`'s shortest leads: a servo lag of 7.5 ms fitted at 10 ms left a
#: remainder of the step response that `unsteady-aero` took up beside it.
SHORT = (0.0025, 0.005, 0.0075)
#: The static nonlinearities of the Hammerstein / Wiener members and their sizes, as
#: fractions of the largest deflection (`bind` makes them radians).
NONLINEAR = {"saturation": (0.5, 0.75), "dead-band": (0.1, 0.2), "backlash": (0.1, 0.2)}
#: Their lags [s]: the grid tried with every size; the chosen member's lag is then refined
#: on `LAGS` up to 0.1 s (`refine`; `SHORT` is not part of that grid).
NONLINEAR_LAGS = (0.02, 0.05)
#: The rate limits, as the time [s] the servo takes to cross the flights' largest
#: deflection (`bind` makes them rad/s: that deflection over the time; a property of the
#: servo and the manoeuvre's size, not of the sample rate or the surface's ripple), and
#: their lags [s].
RATE_LIMITS = (0.05, 0.1, 0.2)
RATE_LAGS = (0.02, 0.05)


def static(x, kind: str, size: float, xp=np, play=backlash):
    """The nonlinearity `kind` of `size` [rad] on the deflection perturbation `x`; `xp` the
    array module and `play` the backlash (`_filters.backlash`; a traced one in the design's
    JAX control map)."""
    if kind == "saturation":
        return xp.clip(x, -size, size)
    if kind == "dead-band":
        return xp.sign(x) * xp.maximum(xp.abs(x) - size, 0.0)
    return play(x, size)


def actuator_filter(x: np.ndarray, dt: float, variant: tuple) -> np.ndarray:
    """`x` through the servo `variant` (a member of `ACTUATOR_FILTERS`: its kind, then its
    parameters); steady before the first sample.

    - `("lag", tau)`, `("delay", T)`: as `lagged`;
    - `("lag-delay", tau, T)`: delayed by `T`, then a first-order lag `tau`;
    - `("second-order", fn, zeta)`: `y'' = wn^2 (x - y) - 2 zeta wn y'`, `wn = 2 pi fn`
      (bilinear transform);
    - `("rate-limit", tau, rmax)`: a first-order lag whose rate is clipped to `rmax` [/s];
      these two step exactly from the midpoint of each sample interval, as `lagged`;
    - `("asymmetric", tau_up, tau_down)`: a first-order lag with `tau_up` while the input is
      above the output, `tau_down` otherwise;
    - `(kind, tau, size, order)` with `kind` one of `NONLINEAR`: the static nonlinearity
      (`static`, `size` in radians) then a first-order lag `tau` (`order="before"`,
      Hammerstein) or the lag first (`"after"`, Wiener).
    """
    kind, *p = variant
    if kind in ("lag", "delay"):
        return lagged(x, dt, kind, p[0])
    if kind == "lag-delay":
        return lagged(lagged(x, dt, "delay", p[1]), dt, "lag", p[0])
    if kind == "second-order":
        return second_order(x, dt, p[0], p[1])
    if kind == "rate-limit":
        k, step = 1.0 - np.exp(-dt / p[0]), p[1] * dt
        return stepped(x, lambda e: min(max(k * e, -step), step))
    if kind == "asymmetric":
        ku, kd = 1.0 - np.exp(-dt / p[0]), 1.0 - np.exp(-dt / p[1])
        return stepped(x, lambda e: (ku if e > 0.0 else kd) * e)
    if kind in NONLINEAR:
        tau, size, order = p
        if order == "before":
            return lagged(static(x, kind, size), dt, "lag", tau)
        return static(lagged(x, dt, "lag", tau), kind, size)
    raise ValueError(f"unknown actuator filter {variant!r}")


#: `actuator-dynamics`' members, simplest first (of members that fit alike, the first is
#: reported: a rate limit that never binds is a plain lag). The nonlinear members' sizes are
#: fractions here; `bind` turns them into radians.
ACTUATOR_FILTERS = (
    tuple(("lag", t) for t in SHORT + LAGS) + tuple(("delay", t) for t in SHORT + LAGS)
    + tuple(("lag-delay", t, T) for t in (0.02, 0.05, 0.1) for T in (0.02, 0.05))
    + tuple(("second-order", fn, z) for fn in (4.0, 8.0, 16.0) for z in (0.5, 0.8))
    + tuple(("rate-limit", t, r) for t in RATE_LAGS for r in RATE_LIMITS)
    + tuple(("asymmetric", a, b) for a, b in ((0.02, 0.1), (0.1, 0.02), (0.03, 0.07),
                                               (0.07, 0.03)))
    + tuple((k, t, s, order) for k, sizes in NONLINEAR.items() for order in ("before", "after")
            for t in NONLINEAR_LAGS for s in sizes)
)


def filter_text(variant: tuple) -> str:
    """A member of `ACTUATOR_FILTERS` in words (`"first-order lag, tau = 0.05 s"`, ...)."""
    kind, *p = variant
    if kind in NONLINEAR:
        what = {"saturation": f"saturation at {p[1]:.3g} rad",
                "dead-band": f"dead band of {p[1]:.3g} rad",
                "backlash": f"backlash of {p[1]:.3g} rad"}[kind]
        lag = f"first-order lag, tau = {p[0]:g} s"
        return f"{what}, then {lag}" if p[2] == "before" else f"{lag}, then {what}"
    return {"lag": lambda: f"first-order lag, tau = {p[0]:g} s",
            "delay": lambda: f"delay {p[0]:g} s",
            "lag-delay": lambda: f"delay {p[1]:g} s and first-order lag, tau = {p[0]:g} s",
            "second-order": lambda: f"second-order lag, {p[0]:g} Hz, damping {p[1]:g}",
            "rate-limit": lambda: f"first-order lag, tau = {p[0]:g} s, rate limit {p[1]:.3g}/s",
            "asymmetric": lambda: f"direction-dependent lag, tau = {p[0]:g} s rising, "
                                  f"{p[1]:g} s falling"}[kind]()


def acting_all(command: np.ndarray, dt: float, cutoff: float, variants) -> np.ndarray:
    """The acting deflection's cycle-averaged part under each servo of `variants`, `(n,
    len(variants))`: the servo acts on the deflection perturbation `command` (both parts,
    `Signals.commanded`), and its output is split as the loads it drives were
    (`_signals.averaged`, below `cutoff` [Hz]; all outputs in one call). A nonlinear servo
    does not commute with the split: a direction-dependent lag or a rate limit on the
    cycle-averaged deflection, whose steps the split has smoothed, is not the servo on the
    steps."""
    return averaged(np.stack([actuator_filter(command, dt, v) for v in variants]), dt,
                    cutoff).T


def acting(command: np.ndarray, dt: float, cutoff: float, variant: tuple) -> np.ndarray:
    """The acting deflection's cycle-averaged part under the servo `variant` (`acting_all`)."""
    return acting_all(command, dt, cutoff, (variant,))[:, 0]


def _all_columns(s: Signals, load, variants) -> np.ndarray:
    return s.over_whole(AXIS_INPUT[axis_of(load)],
                        lambda d: acting_all(d, s.dt, s.cutoff, variants))


def _columns(s: Signals, load, variant, h, dh):
    return _all_columns(s, load, (variant,))


#: The lags a nonlinear or rate-limited member's lag is refined on [s].
REFINED_LAGS = LAGS[:6]


def refine(variant: tuple) -> tuple:
    """The members like `variant` with its lag on `REFINED_LAGS`: a servo's lag and its
    nonlinearity are found together, and the lag a coarse grid leaves over is what a second
    family (`unsteady-aero`'s lag) would take up. Linear members are on that grid already."""
    kind, *p = variant
    if kind == "rate-limit" or kind in NONLINEAR:
        return tuple((kind, t, *p[1:]) for t in REFINED_LAGS)
    return ()


def _bind(effect: Effect, engine, idx) -> Effect:
    """The members with their nonlinearities sized on the fitting units' largest deflection
    of the manoeuvred axis's control (the 99th percentile of `|d|`, as commanded: the servo's
    input, `Signals.commanded`) and their rate limits on the time a servo would take to
    cross it (`RATE_LIMITS`); members that cannot be sized (a control that never moves) go."""
    axis = axis_of(engine.own[0]) if engine.own else "lon"
    d = [np.abs(engine.units[i].signals.commanded(AXIS_INPUT[axis])) for i in idx
         if AXIS_INPUT[axis] in engine.units[i].signals.slow]
    largest = float(np.percentile(np.concatenate(d), 99.0)) if d else 0.0
    out = []
    for v in effect.variants:
        if v[0] == "rate-limit":
            if largest > 0.0:
                out.append((v[0], v[1], largest / v[2]))
        elif v[0] not in NONLINEAR:
            out.append(v)
        elif largest > 0.0:
            out.append((v[0], v[1], v[2] * largest, *v[3:]))
    return dataclasses.replace(effect, variants=tuple(out))


EFFECT = Effect(
    "actuator-dynamics",
    "the acting deflection is the commanded one through a servo: a lag, a delay, both, a "
    "second-order servo, a rate limit, a direction-dependent lag, a saturation, dead band "
    "or backlash before or after a lag",
    "averaged",
    _columns,
    ACTUATOR_FILTERS,
    replaces_input=True,
    all_columns=_all_columns,
    sized=True,
    bind=_bind,
    refine=refine,
)
