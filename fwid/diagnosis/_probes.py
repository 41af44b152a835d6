"""Probes: deterministic structure that no catalogue entry describes.

A catalogue effect (`_catalogue/`) is named only when it explains the gap better than any of
these. Each probe is a generic, low-order family of regressors of the cycle-averaged loads,
fitted and tested exactly like a catalogue effect (the cross-fit of `_significance.py`, in the
same forward selection). When a probe is the first to enter, the residual is predictable from
what was measured but no catalogue entry explains it: the verdict is `"unexplained"`, with the
signals the probe leans on (`drivers`). Without them, an effect outside the catalogue (the
weight's moment of an offset centre of gravity, a battery draining) is named after whichever
catalogue entry it happens to correlate with, which is the wrong answer looking like a right
one.

- `attitude`: the load follows the attitude angle (theta or phi), which Eqs. (2-6) leave out.
- `drift`: a trend over the flight common to all flights (battery sag, temperature).

`drivers` says which measured signals a selected probe leans on.

No probe may contain the states' rates, or filtered states (a lagged state is the state minus
its rate times the lag): the loads are reconstructed from those rates (Section III), so such a
probe would "explain" any residual, measurement noise included.
"""

from __future__ import annotations

import math

import numpy as np

from ._attribution import Engine, acts_on
from ._catalogue import Effect, axis_of, slow_of

#: The attitude angle of each axis.
ATTITUDE = {"lon": "theta", "lat": "phi"}


def _attitude(s, load, variant, h, dh):
    return slow_of(s, ATTITUDE[axis_of(load)])[:, None]


def elapsed(t: np.ndarray) -> np.ndarray:
    """Time since the first sample, per 10 s (columns of the size of the others)."""
    return (t - t[0]) / 10.0


def _drift(s, load, variant, h, dh):
    t = elapsed(s.t)
    return np.stack([t, t * t], axis=1)


PROBES: tuple[Effect, ...] = (
    Effect("attitude", "loads follow the attitude angle", "averaged", _attitude,
           labels=lambda load: (ATTITUDE[axis_of(load)],), probe=True),
    Effect("drift", "a trend over the flight common to all flights", "averaged", _drift,
           labels=lambda load: ("time", "time"), probe=True, crosses_axes=True),
)

#: Names of the probes.
PROBE_NAMES = tuple(p.name for p in PROBES)


def drivers(engine: Engine, idx, probe: Effect, variant, sigma2: dict) -> list[dict]:
    """The measured signals a probe leans on, most first: per signal, the RMS over the units
    `idx` of its columns' contribution (coefficient x column, fitted with the baseline on
    `idx`), relative to the baseline's RMS error, summed over the probe's loads."""
    weight: dict[str, float] = {}
    model = ((probe, variant),)
    for ch in engine.channels(probe.band):
        if not acts_on(variant, ch[0]):
            continue
        theta, _ = engine.fit(idx, ch, model)
        cols = np.concatenate([engine.design(i, ch, model) for i in idx])
        names = probe.labels(ch[0]) if probe.labels else (probe.name,)
        k = len(names)
        part = cols[:, -k:] * theta[-k:]
        for j, name in enumerate(names):
            w = float(np.std(part[:, j]) / math.sqrt(sigma2[ch]))
            weight[name] = weight.get(name, 0.0) + w
    total = sum(weight.values()) or 1.0
    return [{"signal": n, "share_pct": 100.0 * w / total}
            for n, w in sorted(weight.items(), key=lambda kv: -kv[1])]
