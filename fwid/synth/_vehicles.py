"""Randomised vehicles: DelFly-like, but not the paper's, for benchmarks that must not be
tuned to one set of parameters."""

from __future__ import annotations

import numpy as np

from ._delfly import DELFLY, FLAP_LAT_PARAMS, FLAP_LON_PARAMS, LAT_PARAMS, LON_PARAMS, DelFly

#: The parameters `random_vehicle` draws: every cycle-averaged derivative (Tables 1, 4) and
#: every flapping Fourier coefficient (Table 7 and the lateral ones).
RANDOM_PARAMS = LON_PARAMS + LAT_PARAMS + FLAP_LON_PARAMS + FLAP_LAT_PARAMS


def stable(vehicle: DelFly) -> bool:
    """Whether both cycle-averaged models (Eqs. 7 and 8) have all eigenvalues in the open
    left half-plane."""
    return all(np.max(vehicle.eigenvalues(a).real) < 0 for a in ("lon", "lat"))


def random_vehicle(seed: int, spread: float = 0.3, base: DelFly = DELFLY,
                   max_draws: int = 1000) -> DelFly:
    """A DelFly whose every parameter of `RANDOM_PARAMS` is `base`'s times an independent
    `U(1 - spread, 1 + spread)` factor (so within +-30 % by default, sign kept); mass,
    inertia, trim and flapping frequency are `base`'s. Drawn from
    `numpy.random.default_rng(seed)` and redrawn (same generator) until `stable`, so the
    result is deterministic by `seed`. Raises `RuntimeError` after `max_draws` draws."""
    if not 0 <= spread < 1:
        raise ValueError(f"spread must be in [0, 1), got {spread}")
    rng = np.random.default_rng(seed)
    for _ in range(max_draws):
        f = rng.uniform(1 - spread, 1 + spread, len(RANDOM_PARAMS))
        v = base.replace(**{k: float(getattr(base, k) * fk) for k, fk in zip(RANDOM_PARAMS, f)})
        if stable(v):
            return v
    raise RuntimeError(f"no stable vehicle in {max_draws} draws (spread {spread})")
