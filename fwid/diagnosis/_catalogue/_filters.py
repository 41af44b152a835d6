"""Causal filters of a sampled signal: the lags, delays and servo forms the families use."""

from __future__ import annotations

import numpy as np
from scipy.signal import bilinear, lfilter, lfilter_zi


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


def second_order(x: np.ndarray, dt: float, fn: float, zeta: float) -> np.ndarray:
    """`y'' = wn^2 (x - y) - 2 zeta wn y'`, `wn = 2 pi fn` (bilinear transform), steady at
    the first sample."""
    wn = 2.0 * np.pi * fn
    b, a = bilinear([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn], fs=1.0 / dt)
    y, _ = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])
    return y


def stepped(x: np.ndarray, gain) -> np.ndarray:
    """`y_k = y_{k-1} + gain(m_k - y_{k-1})`, `m_k` the midpoint of the sample interval,
    started at `x_0`: the nonlinear first-order members, stepped on Python floats."""
    xm = (0.5 * (x + np.concatenate([x[:1], x[:-1]]))).tolist()
    out, prev = [], float(x[0])
    for xi in xm:
        prev += gain(xi - prev)
        out.append(prev)
    return np.asarray(out)


def backlash(x: np.ndarray, width: float) -> np.ndarray:
    """A linkage with play `width`: the output follows the input only once the input has
    moved `width / 2` past it (hysteresis, memory), started centred."""
    out, prev, h = [], float(x[0]), 0.5 * width
    for xi in x.tolist():
        if xi > prev + h:
            prev = xi - h
        elif xi < prev - h:
            prev = xi + h
        out.append(prev)
    return np.asarray(out)
