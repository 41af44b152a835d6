"""The catalogue of unmodelled effects (the effect names) as augmentations of the model.

Each `Effect` adds a group of regressors to the cycle-averaged linear load model of Eqs. (2-6)
(`base_columns`), shared by all flights. None of them is tuned to a particular simulator: each
is the generic first term of its physical family.

- `flap-coupling`: the flapping loads of Eq. (12) change with the slow motion. The flight's own
  flapping series `h(phi)` (and its phase derivative `h'`, a shift of the harmonics) is
  multiplied by each cycle-averaged state and input: `x h`, `x h'` (amplitude and phase
  modulation, the sidebands `n f +- f_manoeuvre` of a linear time-periodic system).
- `nonlinear-aero`: second-order terms of the cycle-averaged states of the load's axis:
  `x^2`, `x|x|` and the cross products (the next terms of the Taylor series behind Eq. 2;
  `|x| x` is quadratic drag), as a family of matched capacity: its size, from one term to the
  whole group (`QUADRATIC_SUBSETS`), is chosen by leave-one-flight-out error on the fitting
  flights, so that a single quadratic term is not lost in the noise the other eight columns
  fit, and the whole group wins only when it predicts flights it was not fitted to.
- `lon-lat-coupling`: the other axis's states and control drive the load (Eqs. 2 and 5 with
  the cross terms the paper leaves out).
- `actuator-dynamics`: the deflection that acts is the measured one through a causal filter:
  `d_eff` replaces `d` in the load's own model (no new coefficient, the control derivative
  acts on `d_eff`). A family (`ACTUATOR_FILTERS`): a first-order lag, a pure delay, both, a
  second-order servo, a rate limit, a direction-dependent lag, each of one or two numbers
  from a grid, the member chosen by leave-one-flight-out error on the fitting flights, as
  `nonlinear-aero`'s size. One column only, so it cannot soak up unrelated misfit.
- `unsteady-aero`: part of the state-dependent loads follows the states late (a lagging
  wake, Wagner/Kuessner-like): the lagging part `lag(x) - x` of the axis's states through a
  first-order lag of time constant from `LAGS`, one coefficient per state. A load is never
  given the lag of the state it is reconstructed from (X: u, Z: w, M: q, Y: v, L and N: p,
  r): `lag(x) - x` is about `-tau x'`, and the noise of `x'` is the load's own noise
  (Section III), so such a column would "explain" measurement noise. The other states carry
  the effect (M through w and u, Z through q and u, ...). Those rates also carry what a gust
  does to the other loads, so when the residual stays red after it (`_disturbance.py`) it was
  a proxy of a disturbance: it is set aside and the selection runs again without it
  (`random-disturbance` unless that names an effect). The measured states are lagged, not
  states simulated from the deflection by a linear model: such noise-free states predict
  what the measured states' noise hides from the baseline (errors in the variables), and to
  first order in `tau` their lagging parts `-tau (A x + B d)` lie in the span of the states
  and the deflection, so they add nothing.
- `time-offset`: the logged deflection is late against the states (a clock offset between the
  logs; `actuator-dynamics` covers the deflection acting *after* it is logged, which a
  time offset of the other sign cannot be told from): the deflection shifted earlier by a lead
  from `LEADS` replaces the measured one, like `actuator-dynamics`.
- `flap-frequency`: the cycle-averaged loads follow the slow variation of the flapping
  frequency `f` (thrust grows with it), which Eqs. (1-6) leave out: `df` and `df^2` (`df`
  the cycle-averaged `f` minus its flight median), at once or through a first-order lag from
  `FREQUENCY_LAGS`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from scipy.signal import bilinear, lfilter, lfilter_zi

from ._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, Signals, other

#: Time constants / delays [s] tried by `actuator-dynamics` and `unsteady-aero`.
LAGS = (0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.14, 0.2)
#: Leads [s] tried by `time-offset`.
LEADS = (0.01, 0.02, 0.03, 0.05, 0.07, 0.1)
#: Time constants [s] tried by `flap-frequency` (0: none).
FREQUENCY_LAGS = (0.0, 0.1, 0.2, 0.4)
#: The states each load is reconstructed from (their rates are in it, Section III).
OWN_STATES = {"X": ("u",), "Z": ("w",), "M": ("q",), "Y": ("v",), "L": ("p", "r"),
              "N": ("p", "r")}


def axis_of(load: str) -> str:
    return "lon" if load in AXIS_LOADS["lon"] else "lat"


def _slow(s: Signals, name: str) -> np.ndarray:
    return s.slow.get(name, np.zeros(s.n))


def base_columns(s: Signals, load: str, band: str) -> np.ndarray:
    """Global regressors of the baseline model of `load` in `band`: the states and control
    of its axis (Eqs. 2 and 5), cycle-averaged below the split; above it, their parts above the
    split (what a step input puts there; the flapping series itself, Eq. 12, is local)."""
    a = axis_of(load)
    src = s.slow if band == "averaged" else s.fast
    return np.stack([src.get(x, np.zeros(s.n)) for x in AXIS_STATES[a] + (AXIS_INPUT[a],)],
                    axis=1)


def _flap_coupling(s, load, variant, h, dh):
    xs = [_slow(s, x) for x in AXIS_STATES["lon"] + AXIS_STATES["lat"] + ("de", "dr")]
    return np.stack([x * h for x in xs] + [x * dh for x in xs], axis=1)


def quadratic_names(axis: str) -> list[str]:
    """The names of `nonlinear-aero`'s columns on `axis`, in their order: per state `xx` and
    `x|x|`, then the cross products."""
    xs = AXIS_STATES[axis]
    out = []
    for x in xs:
        out += [f"{x}{x}", f"{x}|{x}|"]
    out += [f"{xs[i]}{xs[j]}" for i in range(len(xs)) for j in range(i + 1, len(xs))]
    return out


#: `nonlinear-aero`'s variants: subsets of its columns (indices into `quadratic_names`), from
#: one term to the whole group, chosen by leave-one-flight-out error (`Effect.sized`): each
#: single term, each state's pair, the even part (squares, cross products), the odd part
#: (`x|x|`), and all (`None`).
QUADRATIC_SUBSETS = ((None,) + tuple((k,) for k in range(9))
                     + ((0, 1), (2, 3), (4, 5), (0, 2, 4, 6, 7, 8), (1, 3, 5)))


def _nonlinear(s, load, variant, h, dh):
    xs = [_slow(s, x) for x in AXIS_STATES[axis_of(load)]]
    cols = []
    for x in xs:
        cols += [x * x, x * np.abs(x)]
    for i in range(len(xs)):
        for j in range(i + 1, len(xs)):
            cols.append(xs[i] * xs[j])
    if variant is not None:
        cols = [cols[k] for k in variant]
    return np.stack(cols, axis=1)


def _coupling(s, load, variant, h, dh):
    a = other(axis_of(load))
    return np.stack([_slow(s, x) for x in AXIS_STATES[a] + (AXIS_INPUT[a],)], axis=1)


def lagged(x: np.ndarray, dt: float, kind: str, tau: float) -> np.ndarray:
    """`x` through a first-order lag (`kind="lag"`, time constant `tau`) or delayed by `tau`
    (`kind="delay"`); the signal is taken as steady before its first sample."""
    if kind == "delay":
        t = np.arange(len(x)) * dt
        return np.interp(t - tau, t, x)
    a = np.exp(-dt / tau)
    # y_k = a y_{k-1} + (1 - a) (x_k + x_{k-1}) / 2, started steady at x_0
    b = (0.5 * (1.0 - a), 0.5 * (1.0 - a))
    y, _ = lfilter(b, (1.0, -a), x, zi=lfilter_zi(b, (1.0, -a)) * x[0])
    return y


def actuator_filter(x: np.ndarray, dt: float, variant: tuple) -> np.ndarray:
    """`x` through the causal filter `variant` (a member of `ACTUATOR_FILTERS`: its kind,
    then its parameters); steady before the first sample.

    - `("lag", tau)`, `("delay", T)`: as `lagged`;
    - `("lag-delay", tau, T)`: delayed by `T`, then a first-order lag `tau`;
    - `("second-order", fn, zeta)`: `y'' = wn^2 (x - y) - 2 zeta wn y'`, `wn = 2 pi fn`
      (bilinear transform);
    - `("rate-limit", tau, rmax)`: a first-order lag whose rate is clipped to `rmax` [/s];
      these two step exactly from the midpoint of each sample interval, as `lagged`;
    - `("asymmetric", tau_up, tau_down)`: a first-order lag with `tau_up` while the input is
      above the output, `tau_down` otherwise.
    """
    kind, *p = variant
    if kind in ("lag", "delay"):
        return lagged(x, dt, kind, p[0])
    if kind == "lag-delay":
        return lagged(lagged(x, dt, "delay", p[1]), dt, "lag", p[0])
    if kind == "second-order":
        wn = 2.0 * np.pi * p[0]
        b, a = bilinear([wn * wn], [1.0, 2.0 * p[1] * wn, wn * wn], fs=1.0 / dt)
        y, _ = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])
        return y
    if kind in ("rate-limit", "asymmetric"):  # stepped sample by sample, on Python floats
        if kind == "rate-limit":
            k, step = 1.0 - np.exp(-dt / p[0]), p[1] * dt

            def gain(e):
                return min(max(k * e, -step), step)
        else:
            ku, kd = 1.0 - np.exp(-dt / p[0]), 1.0 - np.exp(-dt / p[1])

            def gain(e):
                return (ku if e > 0.0 else kd) * e
        xm = (0.5 * (x + np.concatenate([x[:1], x[:-1]]))).tolist()  # the steps' midpoints
        out, prev = [], float(x[0])
        for xi in xm:
            prev += gain(xi - prev)
            out.append(prev)
        return np.asarray(out)
    raise ValueError(f"unknown actuator filter {variant!r}")


#: `actuator-dynamics`' members: causal filters of the measured deflection of one or two
#: parameters each (`actuator_filter`), the member chosen by leave-one-flight-out error on the
#: fitting flights (`Effect.sized`), as `nonlinear-aero`'s subsets. The grids are generic
#: (servo bandwidths of a few to tens of Hz, rates of a fraction to tens of rad/s), not a
#: simulator's values.
ACTUATOR_FILTERS = (
    tuple(("lag", t) for t in LAGS) + tuple(("delay", t) for t in LAGS)
    + tuple(("lag-delay", t, T) for t in (0.02, 0.05, 0.1) for T in (0.02, 0.05))
    + tuple(("second-order", fn, z) for fn in (4.0, 8.0, 16.0) for z in (0.5, 0.8))
    + tuple(("rate-limit", t, r) for t in (0.02, 0.05) for r in (1.0, 3.0, 10.0))
    + tuple(("asymmetric", a, b) for a, b in ((0.02, 0.1), (0.1, 0.02), (0.03, 0.07),
                                               (0.07, 0.03)))
)


def filter_text(variant: tuple) -> str:
    """A member of `ACTUATOR_FILTERS` in words (`"first-order lag, tau = 0.05 s"`, ...)."""
    kind, *p = variant
    return {"lag": lambda: f"first-order lag, tau = {p[0]:g} s",
            "delay": lambda: f"delay {p[0]:g} s",
            "lag-delay": lambda: f"delay {p[1]:g} s and first-order lag, tau = {p[0]:g} s",
            "second-order": lambda: f"second-order lag, {p[0]:g} Hz, damping {p[1]:g}",
            "rate-limit": lambda: f"first-order lag, tau = {p[0]:g} s, rate limit {p[1]:g}/s",
            "asymmetric": lambda: f"direction-dependent lag, tau = {p[0]:g} s rising, "
                                  f"{p[1]:g} s falling"}[kind]()


def _actuator(s, load, variant, h, dh):
    d = _slow(s, AXIS_INPUT[axis_of(load)])
    return actuator_filter(d, s.dt, variant)[:, None]


def lagging_part(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """`lag(x) - x`: the part of `x` a first-order lag of `tau` holds back."""
    return lagged(x, dt, "lag", tau) - x


def frequency_deviation(f: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """The flapping frequency minus its median over the flight, through a first-order lag
    `tau` (0: none)."""
    df = f - np.median(f)
    return lagged(df, dt, "lag", tau) if tau else df


def unsteady_states(load: str) -> tuple[str, ...]:
    """The states whose lagging part `unsteady-aero` gives `load` (not its own)."""
    return tuple(x for x in AXIS_STATES[axis_of(load)] if x not in OWN_STATES[load])


def _unsteady(s, load, tau, h, dh):
    xs = [_slow(s, x) for x in unsteady_states(load)]
    return np.stack([lagging_part(x, s.dt, tau) for x in xs], axis=1)


def _time_offset(s, load, lead, h, dh):
    d = _slow(s, AXIS_INPUT[axis_of(load)])
    return lagged(d, s.dt, "delay", -lead)[:, None]


def _flap_frequency(s, load, tau, h, dh):
    df = frequency_deviation(_slow(s, "f"), s.dt, tau)
    return np.stack([df, df * df], axis=1)


@dataclasses.dataclass(frozen=True)
class Effect:
    """One candidate effect: `columns(signals, load, variant, h, dh)` returns the regressors
    it adds to the model of `load` in `band` (`h`, `dh`: the flight's flapping series of that
    load and its phase derivative); `variants` are the discrete choices fitted by trying each
    (e.g. time constants). With `replaces_input`, the single column returned replaces the
    control column of the baseline instead of being added. `labels(load)`, if given, names
    the measured signal behind each column (the drivers of an unexplained gap)."""

    name: str
    description: str
    band: str
    columns: Callable = dataclasses.field(repr=False)
    variants: tuple = (None,)
    replaces_input: bool = False
    labels: Callable | None = dataclasses.field(default=None, repr=False, compare=False)
    #: Its columns carry states' rates, which integrate what an unmeasured disturbance does
    #: to the other loads: it may be a proxy of gusts (`_diagnose.py` checks the colour).
    rates: bool = False
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


#: The candidate effects that `fwid.diagnose` tries, in this order; their names are the
#: effect names of `diagnosis.json` and of `fwid simulate --effect`.
CATALOGUE: tuple[Effect, ...] = (
    Effect(
        "flap-coupling",
        "flapping loads modulated by the body motion and inputs (time scales coupled)",
        "flapping",
        _flap_coupling,
        crosses_axes=True,
    ),
    Effect(
        "nonlinear-aero",
        "cycle-averaged loads quadratic in the states (x^2, x|x|, cross products)",
        "averaged",
        _nonlinear,
        QUADRATIC_SUBSETS,
        sized=True,
    ),
    Effect(
        "lon-lat-coupling",
        "the other axis's states and control drive the loads",
        "averaged",
        _coupling,
        crosses_axes=True,
    ),
    Effect(
        "actuator-dynamics",
        "the acting deflection is the measured one through a causal filter (a lag, a delay, "
        "both, a second-order servo, a rate limit, a direction-dependent lag)",
        "averaged",
        _actuator,
        ACTUATOR_FILTERS,
        replaces_input=True,
        sized=True,
    ),
    Effect(
        "unsteady-aero",
        "part of the state-dependent loads lags the states (a lagging wake)",
        "averaged",
        _unsteady,
        LAGS,
        labels=unsteady_states,
        rates=True,
    ),
    Effect(
        "time-offset",
        "the logged deflection is late against the states (the response leads it)",
        "averaged",
        _time_offset,
        LEADS,
        replaces_input=True,
        labels=lambda load: (AXIS_INPUT[axis_of(load)],),
    ),
    Effect(
        "flap-frequency",
        "the cycle-averaged loads follow the flapping frequency",
        "averaged",
        _flap_frequency,
        FREQUENCY_LAGS,
        labels=lambda load: ("f", "f"),
        crosses_axes=True,
    ),
)

#: Effect names the diagnosis can return (with "none").
EFFECT_NAMES = tuple(e.name for e in CATALOGUE)


def get_effect(name: str) -> Effect:
    for e in CATALOGUE:
        if e.name == name:
            return e
    raise ValueError(f"unknown effect {name!r}; choose from {', '.join(EFFECT_NAMES)}")
