"""Noise levels by maximum likelihood, then the Rauch-Tung-Striebel smoother, for a batch
of independent problems of one length (vmapped: takes, or takes x attitude axes).

The noise levels come from the data: the smoother's cut-off `f_c` of the slow part, the
bandwidth `f_h` of the flapping coefficients and (with a gyro) the gyro's noise relative to
the attitude's are chosen on a grid (`_model.CUTOFFS`, ...) by the innovations'
log-likelihood, with the overall noise scale concentrated out (it is `mean(nu^2 / S)`);
the likelihood is evaluated on at most `ML_WINDOW` samples from the middle of the take.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from . import _model as mdl

#: Samples used to choose the noise levels (from the middle of a take).
ML_WINDOW = 2000
#: Largest memory (bytes) of the stored smoother gains of one vmapped call.
GAIN_BYTES = 2e8

_JIT = {}


def _fns():
    if not _JIT:
        import jax

        from ._kalman import concentrated_loglik, filter_stats, smooth

        stats = jax.vmap(jax.vmap(filter_stats, in_axes=(None, 0, None, 0, None, None, None,
                                                         None, None)),
                         in_axes=(None, 0, 0, None, 0, 0, 0, 0, None))
        _JIT["grid"] = jax.jit(lambda *a: concentrated_loglik(stats(*a)))
        _JIT["smooth"] = jax.jit(jax.vmap(smooth, in_axes=(None, 0, 0, 0, 0, 0, 0, 0, None)))
    return _JIT


class Smoothed(NamedTuple):
    """Smoothed totals `(M, N, c)` (slow part plus harmonics) and the chosen noise levels."""

    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    bias: np.ndarray | None  # (M, c)
    sigma: np.ndarray        # (M,) noise std of position/attitude measurements
    sigma_gyro: np.ndarray | None
    cutoff: np.ndarray       # (M,) Hz
    coeff_bandwidth: np.ndarray  # (M,) Hz
    params: list             # (cutoff, coeff_bandwidth, gyro_ratio) per problem


def smooth_batch(z, mask, phase, omega, dt: float, *, gyro=None, gyro_mask=None, u=None,
                 scale: float = 1e-6, params=None) -> Smoothed:
    """Smooth `M` independent problems of one length `N`, each with `c` data columns that
    share the noise levels.

    **Arguments:**
    - `z` `(M, N, c)`: position (attitude) measurements; `mask` `(M, N)`: where they exist;
    - `phase`, `omega` `(M, N)`: flapping phase and angular frequency (`_model.phase_of`);
    - `dt`: sample step (s);
    - `gyro` `(M, N, c)`, `gyro_mask` `(M, N)`: rate measurements (with a bias state), or None;
    - `u` `(M, N, c)`: known input of the first state per step (the attitude's nominal
      increment), or None;
    - `scale`: the measurement variance guessed, for the diffuse prior;
    - `params`: `(cutoff, coeff_bandwidth, gyro_ratio)` per problem to skip the search.

    **Returns:** a [`Smoothed`][].
    """
    import jax.numpy as jnp

    fns = _fns()
    z = np.asarray(z, float)
    M, N, c = z.shape
    bias = gyro is not None
    n = mdl.n_states(bias)
    rate = 1.0 / dt
    rows = mdl.rows(phase, omega, rate, bias)
    m_meas = 2 if bias else 1
    H = np.stack([rows["pos"]] + ([rows["gyro"]] if bias else []), 2)  # (M, N, m, n)
    Z = np.stack([np.nan_to_num(z)] + ([np.nan_to_num(gyro)] if bias else []), 2)
    MK = np.stack([mask] + ([gyro_mask] if bias else []), 2).astype(bool)
    U = np.zeros((M, N, n, c))
    if u is not None:
        U[:, :, 0, :] = u
    F = mdl.transition(dt, bias)
    P0 = mdl.prior(n, bias, scale)
    m0 = np.zeros((M, n, c))
    first = np.argmax(mask, axis=1)
    m0[:, 0, :] = z[np.arange(M), first]
    omega0 = np.array([np.nanmedian(o) if np.isfinite(o).any() else 2 * np.pi for o in omega])

    def noise(fc, fh, w0, ratio):
        qj, qh = mdl.intensities(dt, fc, fh, w0)
        return mdl.process_noise(dt, qj, qh, bias), np.array([1.0, ratio**2][:m_meas])

    if params is None:
        grid = list(itertools.product(mdl.CUTOFFS, mdl.COEFF_BANDWIDTHS,
                                      mdl.GYRO_RATIOS if bias else (1.0,)))
        lo = max(0, (N - ML_WINDOW) // 2)
        win = slice(lo, min(N, lo + ML_WINDOW))
        Qs = np.stack([[noise(fc, fh, w0, g)[0] for fc, fh, g in grid] for w0 in omega0])
        Rs = np.stack([noise(1, 1, 1, g)[1] for _, _, g in grid])
        m0w = m0.copy()
        fw = np.argmax(mask[:, win], axis=1)
        m0w[:, 0, :] = z[:, win][np.arange(M), fw]
        ll = np.asarray(fns["grid"](jnp.asarray(F), jnp.asarray(Qs), jnp.asarray(H[:, win]),
                                    jnp.asarray(Rs), jnp.asarray(Z[:, win]),
                                    jnp.asarray(MK[:, win]), jnp.asarray(U[:, win]),
                                    jnp.asarray(m0w), jnp.asarray(P0)))
        best = np.argmax(np.where(np.isfinite(ll), ll, -np.inf), axis=1)
        params = [grid[b] for b in best]
    Q = np.stack([noise(fc, fh, w0, g)[0] for (fc, fh, g), w0 in zip(params, omega0)])
    R = np.stack([noise(1, 1, 1, g)[1] for _, _, g in params])
    chunk = max(1, int(GAIN_BYTES // (N * n * n * 8 * 3)))
    xs, acc = [], []
    for a in range(0, M, chunk):
        s = slice(a, a + chunk)
        x, st = fns["smooth"](jnp.asarray(F), jnp.asarray(Q[s]), jnp.asarray(H[s]),
                              jnp.asarray(R[s]), jnp.asarray(Z[s]), jnp.asarray(MK[s]),
                              jnp.asarray(U[s]), jnp.asarray(m0[s]), jnp.asarray(P0))
        xs.append(np.asarray(x))
        acc.append(np.asarray(st))
    x, acc = np.concatenate(xs), np.concatenate(acc)  # (M, N, n, c), (M, 3)
    s2 = acc[:, 1] / np.maximum(acc[:, 2], 1)  # the concentrated noise scale
    out = {k: np.einsum("mkn,mknc->mkc", rows[k], x) for k in ("pos", "vel", "acc")}
    ratio = np.array([p[2] for p in params])
    return Smoothed(out["pos"], out["vel"], out["acc"], x[:, 0, -1, :] if bias else None,
                    np.sqrt(s2), np.sqrt(s2) * ratio if bias else None,
                    np.array([p[0] for p in params]), np.array([p[1] for p in params]),
                    list(params))
