"""The design criteria, the input's parametrisations as maps to basis coefficients, and the
criterion of a model affine in the input as one pytree (compiled once per shape).

Criteria, of the vehicle's information `M` (relative units: both are invariant to the
parameters' scales up to a constant), maximised:

- `"d-optimal"`: `log det M`, the volume of the confidence ellipsoid (Mehra; the classic
  choice, invariant to any reparametrisation);
- `"variances"`: `-sum_i log (M^-1)_ii`, minus twice the log of the geometric mean of the
  predicted standard deviations of the parameters (times their count): what `design.json`
  and `fwid design` report, the geometric-mean ratio over the derivatives.

Parametrisations: the input is `coef(x) @ basis`, a fixed basis `(k, n)` and coefficients
from the free variables `x`: the steps of a piecewise-constant sequence (`A tanh x_j`), or the
sines and cosines of the harmonics of a multisine (free amplitudes and phases, the peak scaled
to `A`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._errors import InputError
from ._affine import Affine
from ._information import log_det, schur
from ._signals import Grid, harmonics, step_index


def log_variances(M: Float[Array, "g g"]) -> Float[Array, ""]:
    """`-sum_i log (M^-1)_ii` of a symmetric positive-definite `M` (Cholesky)."""
    L = jnp.linalg.cholesky(0.5 * (M + M.T))
    Linv = jax.scipy.linalg.solve_triangular(L, jnp.eye(M.shape[0], dtype=M.dtype), lower=True)
    return -jnp.sum(jnp.log(jnp.sum(Linv**2, axis=0)))


#: The design criteria, to be maximised, of the vehicle's information (relative units).
CRITERIA = {"d-optimal": log_det, "variances": log_variances}


def objective(name: str):
    """The criterion function of its name (one-line error for an unknown one)."""
    if name not in CRITERIA:
        raise InputError(f"design: criterion must be one of {', '.join(CRITERIA)}, got "
                         f"{name!r}")
    return CRITERIA[name]


class Steps(eqx.Module):
    """`A tanh(x_j)` held for `1 / switch_rate` s: the coefficients of the step basis."""

    amplitude: Float[Array, ""]

    def __call__(self, x):
        return self.amplitude * jnp.tanh(x)


class Multisine(eqx.Module):
    """`sum_k a_k sin(w_k tau + phi_k)` (`x = (a, phi)`) as coefficients of the sines and
    cosines, its peak scaled to the amplitude."""

    amplitude: Float[Array, ""]
    basis: Float[Array, "k n"]

    def __call__(self, x):
        m = x.shape[0] // 2
        c = jnp.concatenate([x[:m] * jnp.cos(x[m:]), x[:m] * jnp.sin(x[m:])])
        return self.amplitude * c / jnp.max(jnp.abs(c @ self.basis))


def parametrisation(name: str, grid: Grid, amplitude: float, switch_rate: float, band):
    """The basis signals `(k, n)`, the coefficient map (a [`Steps`][] or [`Multisine`][]) and
    a random start of the free variables of the parametrisation `name`."""
    if name not in ("multisine", "steps"):
        raise InputError(f"design: parametrisation must be 'multisine' or 'steps', got "
                         f"{name!r}")
    if name == "multisine":
        freqs = harmonics(grid, (max(band[0], 1e-9), band[1]))
        if freqs.size == 0:
            raise InputError(f"design: no harmonic of 1/{grid.length:g} Hz in the band {band}")
        tau = 2 * np.pi * freqs[:, None] * (grid.t - grid.quiet)[None]
        basis = np.concatenate([np.sin(tau), np.cos(tau)]) * grid.active
        m = freqs.size

        def start(key):
            a, p = jax.random.split(key)
            return jnp.concatenate([jax.random.uniform(a, (m,), minval=0.2),
                                    jax.random.uniform(p, (m,), maxval=2 * jnp.pi)])
        return basis, Multisine(jnp.asarray(float(amplitude)), jnp.asarray(basis)), start
    idx, k = step_index(grid, switch_rate)
    basis = (idx[None, :] == np.arange(k)[:, None]).astype(float)

    def start(key):
        return 1.5 * jax.random.normal(key, (k,))
    return basis, Steps(jnp.asarray(float(amplitude))), start


class AffineLoss(eqx.Module):
    """Minus the criterion of the free variables `x` for a model affine in the input: the
    coefficients, scaled down to the attitude bound (exact: the outputs are linear in them),
    the information a quadratic form in them, the per-flight biases' Schur complement, the
    flights flown and the prior (`base`). A pytree: its arrays are arguments of the compiled
    optimiser, which is compiled once per shape and kept."""

    affine: Affine
    coef: eqx.Module
    base: Float[Array, "g g"]
    bound: Float[Array, ""]
    attitude: int | None = eqx.field(static=True)
    glob: tuple[int, ...] = eqx.field(static=True)
    loc: tuple[int, ...] = eqx.field(static=True)
    criterion: str = eqx.field(static=True)

    def __call__(self, x):
        v = self.coef(x)
        if self.attitude is not None:
            peak = jnp.max(jnp.abs(self.affine.outputs(v)[:, self.attitude]))
            v = v * jnp.where(jnp.isfinite(peak), jnp.minimum(1.0, self.bound / peak), 0.0)
        Mv = schur(self.affine.information(v), self.glob, self.loc)
        return -CRITERIA[self.criterion](Mv + self.base)
