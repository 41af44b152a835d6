"""System-identification input signals (paper Sec. III.A: pulses, doublets, 211 inputs; and
the classical 3211).

Each signal is a function of `(t, start, unit, amplitude)` returning the commanded
deflection perturbation [rad] at the times `t`: zero before `start` (the quiet trim start)
and after the manoeuvre, and a sequence of steps of `unit` seconds each in between. Step
edges are half open, `[edge, next edge)`, with a 1e-9 s tolerance so that sample times that
fall on an edge up to rounding are treated consistently.
"""

from __future__ import annotations

import numpy as np

_EPS = 1e-9


def _steps(t, start, unit, amplitude, pattern) -> np.ndarray:
    """Piecewise-constant signal: `amplitude * pattern[k]` on `[start + k unit,
    start + (k+1) unit)`."""
    if unit <= 0:
        raise ValueError(f"input unit duration must be > 0 s, got {unit}")
    t = np.asarray(t, dtype=float)
    s = (t - start + _EPS) / unit  # position in units since the start
    k = np.floor(s).astype(int)
    inside = (k >= 0) & (k < len(pattern))
    pat = np.asarray(pattern, dtype=float)
    out = np.zeros_like(t)
    out[inside] = amplitude * pat[k[inside]]
    return out


def doublet(t, start, unit, amplitude) -> np.ndarray:
    """Doublet: `+amplitude` for one unit, then `-amplitude` for one unit."""
    return _steps(t, start, unit, amplitude, (1, -1))


def input_3211(t, start, unit, amplitude) -> np.ndarray:
    """3211: `+A` for 3 units, `-A` for 2, `+A` for 1, `-A` for 1 (7 units in all)."""
    return _steps(t, start, unit, amplitude, (1, 1, 1, -1, -1, 1, -1))


def input_211(t, start, unit, amplitude) -> np.ndarray:
    """211: `+A` for 2 units, `-A` for 1, `+A` for 1 (4 units in all)."""
    return _steps(t, start, unit, amplitude, (1, 1, -1, 1))


def pulse(t, start, unit, amplitude) -> np.ndarray:
    """Pulse: `+amplitude` for one unit."""
    return _steps(t, start, unit, amplitude, (1,))


#: Input signals by name.
INPUTS = {"3211": input_3211, "211": input_211, "doublet": doublet, "pulse": pulse}

#: Default unit duration [s] of each input, sized to the DelFly's ~0.9 Hz oscillatory
#: mode (Tables 3 and 6) and its fast aperiodic modes.
DEFAULT_UNIT = {"3211": 0.12, "211": 0.2, "doublet": 0.3, "pulse": 0.2}

#: Number of units of each input.
N_UNITS = {"3211": 7, "211": 4, "doublet": 2, "pulse": 1}


def make_input(name: str, t, start: float, unit: float | None, amplitude: float) -> np.ndarray:
    """The input `name` (one of `INPUTS`) at times `t`; `unit=None` takes `DEFAULT_UNIT`."""
    try:
        fn = INPUTS[name]
    except KeyError:
        raise ValueError(
            f"unknown input {name!r}; choose one of {', '.join(sorted(INPUTS))}"
        ) from None
    return fn(t, start, DEFAULT_UNIT[name] if unit is None else unit, amplitude)
