"""A linear Kalman filter and Rauch-Tung-Striebel smoother in JAX (`lax.scan`), with
missing measurements, time-varying measurement rows and several data columns that share
one covariance (e.g. the three position axes of one model).

    x[k+1] = F x[k] + u[k] + w,  w ~ N(0, Q)        z[k, i] = H[k, i] x[k] + v,  v ~ N(0, R[i])

`z[k, i]` is used where `mask[k, i]`; the scalar measurements of a step are processed one
after the other. The innovation statistics give the Gaussian log-likelihood of the data
(for the noise levels), with the overall scale of `Q`, `R` and `P0` concentrated out.

Each product of a step is an elementwise product summed over a short axis (and, with
`lead`, one small product with the shared `F`), not a matrix product per problem: `vmap`ped
over many problems (the problems as the last axis, `_smoother`), XLA fuses them into loops
over the whole batch; per problem and step the filter takes about half the time of small
matrix products vmapped, the smoother about two thirds.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

#: Innovations of the first samples (the diffuse start) left out of the likelihood.
BURN_IN = 20


def _update(x, P, h, z, r, valid):
    """One scalar measurement `z` `(c,)` (one per column of `x` `(n, c)`) with row `h`
    `(n,)` and variance `r`, where `valid`; for `P` `(n, n)`. Returns the
    updated `x`, `P`, the innovation variance `S`, the innovation `nu` (0 where not valid)
    and the gain `K` (0 where not valid)."""
    Ph = jnp.sum(P * h[None], 1)
    S = jnp.sum(h * Ph, 0) + r
    g = jnp.where(valid, 1.0 / S, 0.0)
    nu = jnp.where(valid, z - jnp.sum(h[:, None] * x, 0), 0.0)
    K = Ph * g
    return x + K[:, None] * nu[None], P - Ph[:, None] * Ph[None] * g, S, nu, K


def _rows(F, A, lead, transpose=False):
    """`F A` (or `F^T A`) along the first axis of `A`; with `lead`, for `F` the identity but
    for its leading `lead x lead` block (only the leading rows of `A` mixed)."""
    if lead is None:
        return jnp.tensordot(F.T if transpose else F, A, 1)
    Fa = F[:lead, :lead].T if transpose else F[:lead, :lead]
    return jnp.concatenate([jnp.tensordot(Fa, A[:lead], 1), A[lead:]], 0)


def _propagate(F, x, P, Q, lead):
    """`F x`, `F P F^T + Q` (symmetrised)."""
    P = jnp.swapaxes(_rows(F, jnp.swapaxes(_rows(F, P, lead), 0, 1), lead), 0, 1)
    return _rows(F, x, lead), 0.5 * (P + jnp.swapaxes(P, 0, 1)) + Q


def _forward(F, Q, H, R, z, mask, u, m0, P0, lead, keep):
    """The filter's scan: the innovation statistics and, with `keep`, each step's predicted
    mean and covariance, gains and weighted innovations `nu / S` (0 where unmeasured)."""
    c, nu_ = m0.shape[1], u.shape[1]

    def step(carry, inp):
        x, P, acc = carry
        h_k, z_k, mk, u_k, k = inp
        x_pred, P_pred, Ks, Ws = x, P, [], []
        for i in range(h_k.shape[0]):
            x, P, S, nu, K = _update(x, P, h_k[i], z_k[i], R[i], mk[i])
            use = mk[i] & (k >= BURN_IN)
            acc = acc + jnp.where(use, jnp.array([c * jnp.log(S), jnp.sum(nu**2) / S, c]), 0.0)
            Ks.append(K)
            Ws.append(nu / S)
        x, P = _propagate(F, x, P, Q, lead)
        x = jnp.concatenate([x[:nu_] + u_k, x[nu_:]], 0)
        return (x, P, acc), ((x_pred, P_pred, jnp.stack(Ks), jnp.stack(Ws)) if keep else None)

    ks = jnp.arange(z.shape[0])
    return jax.lax.scan(step, (m0, P0, jnp.zeros(3)), (H, z, mask, u, ks))


def filter_stats(F, Q, H, R, z, mask, u, m0, P0, lead=None):
    """The innovation statistics of the filter: `(sum log S, sum nu^2 / S, count)`
    over the valid scalar measurements after `BURN_IN` samples, each counted once per data
    column.

    **Arguments:** `F`, `Q` `(n, n)`; `H` `(N, m, n)`; `R` `(m,)`; `z` `(N, m, c)`; `mask`
    `(N, m)`; `u` `(N, n_u, c)`, the known input of the first `n_u` states; `m0` `(n, c)`;
    `P0` `(n, n)`; `lead`: where `F` is the identity but for its leading `lead x lead` block
    (faster), or None.
    """
    (_, _, acc), _ = _forward(F, Q, H, R, z, mask, u, m0, P0, lead, keep=False)
    return acc


def concentrated_loglik(acc: Float[Array, "... 3"]) -> Float[Array, "..."]:
    """The log-likelihood with the noise scale `s` (multiplying Q, R, P0) at its maximum
    `s = mean(nu^2 / S)`: `-1/2 (N log s + sum log S + N)`, up to a constant."""
    logS, nis, n = acc[..., 0], acc[..., 1], acc[..., 2]
    s = nis / jnp.maximum(n, 1.0)
    return -0.5 * (n * jnp.log(s) + logS + n)


def smooth(F, Q, H, R, z, mask, u, m0, P0, lead=None):
    """Smoothed means `(N, n, c)` and the innovation statistics (`filter_stats`), arguments
    as there.

    The Rauch-Tung-Striebel smoother's means in the modified Bryson-Frazier form (Bierman):
    the backward pass carries an adjoint `lam` with `x_smooth = x_pred + P_pred lam` through
    each scalar update (`lam <- h nu / S + (I - h K^T) lam`) and each step (`lam <- F^T lam`);
    no matrix is inverted (the means of the gains `P F^T P_pred^-1`, at a fraction of the cost).
    """
    (_, _, acc), (xp, Pp, K, W) = _forward(F, Q, H, R, z, mask, u, m0, P0, lead, keep=True)

    def backward(lam, inp):
        xp_k, Pp_k, K_k, W_k, h_k = inp
        lam = _rows(F, lam, lead, transpose=True)
        for i in reversed(range(h_k.shape[0])):
            lam = lam + h_k[i][:, None] * (W_k[i] - jnp.sum(K_k[i][:, None] * lam, 0))[None]
        return lam, xp_k + jnp.sum(Pp_k[:, :, None] * lam[None], 1)

    _, xs = jax.lax.scan(backward, jnp.zeros_like(xp[0]), (xp, Pp, K, W, H), reverse=True)
    return xs, acc
