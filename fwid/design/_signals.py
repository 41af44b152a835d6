"""Input signals on a sample grid: the two design parametrisations and the classic inputs.

Every signal is zero before `quiet` (the trim estimate's quiet start) and never above
`amplitude` in magnitude:

- `multisine`: `u = A s / max|s|`, `s(t) = sum_k a_k sin(2 pi f_k (t - quiet) + phi_k)` over
  the harmonics `f_k = k / T` of the manoeuvre length `T = duration - quiet` inside a band,
  with free amplitudes `a_k` and phases `phi_k` (the peak is scaled to `A` exactly);
- `steps`: a free piecewise-constant sequence switching every `1 / switch_rate` s,
  `u_j = A tanh(z_j)` (strictly inside the bound; bang-bang as `|z_j|` grows);
- the classic inputs of equal peak and length: doublet, 3211, Morelli's orthogonal
  phase-optimised multisine (Schroeder phases) and a random binary sequence.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float


class Grid:
    """The time grid of a design: `t` from 0 to `duration` at `rate`, and the manoeuvre
    window after `quiet`."""

    def __init__(self, duration: float, quiet: float, rate: float):
        n = int(np.floor(duration * rate + 1e-9)) + 1
        self.t = np.arange(n) / rate
        self.quiet = float(quiet)
        self.duration = float(self.t[-1])

    @property
    def active(self) -> np.ndarray:
        """1 after the quiet start, 0 before (the sample at `quiet` itself is still 0)."""
        return (self.t > self.quiet + 1e-9).astype(float)

    @property
    def length(self) -> float:
        return self.duration - self.quiet


def harmonics(grid: Grid, band: tuple[float, float]) -> np.ndarray:
    """The harmonics `k / T` of the manoeuvre length `T` inside `band` (Hz)."""
    f0 = 1.0 / grid.length
    k = np.arange(1, int(np.floor(band[1] / f0 + 1e-9)) + 1)
    f = k * f0
    return f[f >= band[0] - 1e-9]


def multisine(theta: Float[Array, " 2m"], grid: Grid, freqs: np.ndarray,
              amplitude: float) -> Float[Array, " n"]:
    """The multisine of amplitudes `theta[:m]` and phases `theta[m:]`, peak `amplitude`."""
    m = freqs.size
    tau = jnp.asarray(grid.t - grid.quiet)
    s = jnp.sum(theta[:m, None] * jnp.sin(2 * jnp.pi * freqs[:, None] * tau[None]
                                           + theta[m:, None]), axis=0)
    s = s * grid.active
    return amplitude * s / jnp.max(jnp.abs(s))


def step_index(grid: Grid, switch_rate: float) -> tuple[np.ndarray, int]:
    """Which step each sample belongs to (`-1` in the quiet start) and how many steps."""
    tau = grid.t - grid.quiet
    k = np.floor(tau * switch_rate - 1e-9).astype(int)
    nsteps = int(np.ceil(grid.length * switch_rate - 1e-9))
    return np.where(grid.active > 0, np.clip(k, 0, nsteps - 1), -1), nsteps


def steps(theta: Float[Array, " m"], grid: Grid, switch_rate: float,
          amplitude: float) -> Float[Array, " n"]:
    """The piecewise-constant sequence `A tanh(theta_j)` held for `1 / switch_rate` s."""
    idx, _ = step_index(grid, switch_rate)
    v = amplitude * jnp.tanh(theta)
    return jnp.where(idx >= 0, v[np.maximum(idx, 0)], 0.0)


def _pattern(grid: Grid, pattern, unit: float, amplitude: float) -> np.ndarray:
    tau = grid.t - grid.quiet
    k = np.floor(tau / unit - 1e-9).astype(int)
    inside = (grid.active > 0) & (k < len(pattern))
    out = np.zeros_like(grid.t)
    out[inside] = amplitude * np.asarray(pattern, float)[k[inside]]
    return out


def input_3211(grid: Grid, amplitude: float, unit: float | None = None) -> np.ndarray:
    """A 3211 (`+A` 3 units, `-A` 2, `+A` 1, `-A` 1) filling the manoeuvre window
    (`unit = T / 7`) unless `unit` is given."""
    unit = grid.length / 7 if unit is None else unit
    return _pattern(grid, (1, 1, 1, -1, -1, 1, -1), unit, amplitude)


def doublet(grid: Grid, amplitude: float, unit: float | None = None) -> np.ndarray:
    """A doublet (`+A`, `-A`), one unit each, `unit = T / 2` unless given."""
    unit = grid.length / 2 if unit is None else unit
    return _pattern(grid, (1, -1), unit, amplitude)


def schroeder_multisine(grid: Grid, amplitude: float,
                        band: tuple[float, float] = (0.0, 3.0)) -> np.ndarray:
    """Morelli's orthogonal phase-optimised multisine for one input: the harmonics of `1/T`
    in `band`, equal power, Schroeder phases `phi_k = -pi k (k - 1) / m` (Morelli 2003's
    starting phases; SIDPAC's `mkmsswp` then refines them for the lowest peak factor), the
    peak scaled to `amplitude`."""
    f = harmonics(grid, (max(band[0], 1e-9), band[1]))
    m = f.size
    k = np.arange(1, m + 1)
    phi = -np.pi * k * (k - 1) / m
    tau = grid.t - grid.quiet
    s = np.sum(np.sin(2 * np.pi * f[:, None] * tau[None] + phi[:, None]), axis=0)
    s = s * grid.active
    return amplitude * s / np.max(np.abs(s))


def random_binary(grid: Grid, amplitude: float, switch_rate: float = 5.0,
                  seed: int = 0) -> np.ndarray:
    """A random binary sequence: `+-A`, switching with probability 1/2 at `switch_rate`
    (MATLAB `idinput`'s `'rbs'`)."""
    idx, m = step_index(grid, switch_rate)
    v = amplitude * np.where(np.random.default_rng(seed).random(m) < 0.5, -1.0, 1.0)
    return np.where(idx >= 0, v[np.maximum(idx, 0)], 0.0)


#: The classic inputs, `name -> fn(grid, amplitude)`.
CLASSIC = {
    "doublet": doublet,
    "3211": input_3211,
    "multisine": schroeder_multisine,
    "random-binary": random_binary,
}
