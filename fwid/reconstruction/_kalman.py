"""A linear Kalman filter and Rauch-Tung-Striebel smoother in JAX (`lax.scan`), with
missing measurements, time-varying measurement rows and several data columns that share
one covariance (e.g. the three position axes of one model).

    x[k+1] = F x[k] + u[k] + w,  w ~ N(0, Q)        z[k, i] = H[k, i] x[k] + v,  v ~ N(0, R[i])

`z[k, i]` is used where `mask[k, i]`; the scalar measurements of a step are processed one
after the other. The innovation statistics give the Gaussian log-likelihood of the data
(for the noise levels), with the overall scale of `Q`, `R` and `P0` concentrated out.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

#: Innovations of the first samples (the diffuse start) left out of the likelihood.
BURN_IN = 20


def _update(x, P, h, z, r, valid):
    """One scalar measurement `z` (one per column of `x`) with row `h` and variance `r`."""
    Ph = P @ h
    S = h @ Ph + r
    K = Ph / S
    nu = z - h @ x
    x = jnp.where(valid, x + K[:, None] * nu[None, :], x)
    P = jnp.where(valid, P - jnp.outer(K, Ph), P)
    P = 0.5 * (P + P.T)
    return x, P, S, nu, K


def filter_stats(F, Q, H, R, z, mask, u, m0, P0):
    """The innovation statistics of the filter: `(sum log S, sum nu^2 / S, count)` over the
    valid scalar measurements after `BURN_IN` samples, each counted once per data column.

    **Arguments:** `F`, `Q` `(n, n)`; `H` `(N, m, n)`; `R` `(m,)`; `z` `(N, m, c)`; `mask`
    `(N, m)`; `u` `(N, n, c)`; `m0` `(n, c)`; `P0` `(n, n)`.
    """
    c = z.shape[-1]

    def step(carry, inp):
        x, P, acc = carry
        h_k, z_k, mk, u_k, k = inp
        for i in range(h_k.shape[0]):
            x, P, S, nu, _ = _update(x, P, h_k[i], z_k[i], R[i], mk[i])
            use = mk[i] & (k >= BURN_IN)
            acc = acc + jnp.where(use, jnp.array([c * jnp.log(S), jnp.sum(nu**2) / S, c]), 0.0)
        x = F @ x + u_k
        P = F @ P @ F.T + Q
        return (x, P, acc), None

    ks = jnp.arange(z.shape[0])
    (_, _, acc), _ = jax.lax.scan(step, (m0, P0, jnp.zeros(3)), (H, z, mask, u, ks))
    return acc


def concentrated_loglik(acc: Float[Array, "... 3"]) -> Float[Array, "..."]:
    """The log-likelihood with the noise scale `s` (multiplying Q, R, P0) at its maximum
    `s = mean(nu^2 / S)`: `-1/2 (N log s + sum log S + N)`, up to a constant."""
    logS, nis, n = acc[..., 0], acc[..., 1], acc[..., 2]
    s = nis / jnp.maximum(n, 1.0)
    return -0.5 * (n * jnp.log(s) + logS + n)


def smooth(F, Q, H, R, z, mask, u, m0, P0):
    """Smoothed means `(N, n, c)` and the innovation statistics (`filter_stats`), arguments
    as there.

    The Rauch-Tung-Striebel smoother's means in the modified Bryson-Frazier form (Bierman):
    the backward pass carries an adjoint `lam` with `x_smooth = x_pred + P_pred lam` through
    each scalar update (`lam <- h nu / S + (I - h K^T) lam`) and each step (`lam <- F^T lam`);
    no matrix is inverted (the means of the gains `P F^T P_pred^-1`, at a fraction of the cost).
    """
    c = z.shape[-1]

    def forward(carry, inp):
        x, P, acc = carry
        h_k, z_k, mk, u_k, k = inp
        x_pred, P_pred, Ks, Ws = x, P, [], []
        for i in range(h_k.shape[0]):
            x, P, S, nu, K = _update(x, P, h_k[i], z_k[i], R[i], mk[i])
            use = mk[i] & (k >= BURN_IN)
            acc = acc + jnp.where(use, jnp.array([c * jnp.log(S), jnp.sum(nu**2) / S, c]), 0.0)
            Ks.append(jnp.where(mk[i], K, 0.0))
            Ws.append(jnp.where(mk[i], nu / S, 0.0))
        return ((F @ x + u_k, F @ P @ F.T + Q, acc),
                (x_pred, P_pred, jnp.stack(Ks), jnp.stack(Ws)))

    ks = jnp.arange(z.shape[0])
    (_, _, acc), (xp, Pp, K, W) = jax.lax.scan(forward, (m0, P0, jnp.zeros(3)),
                                               (H, z, mask, u, ks))

    def backward(lam_next, inp):
        xp_k, Pp_k, K_k, W_k, h_k = inp
        lam = F.T @ lam_next
        for i in reversed(range(h_k.shape[0])):
            lam = lam + h_k[i][:, None] * (W_k[i] - K_k[i] @ lam)[None, :]
        return lam, xp_k + Pp_k @ lam

    _, xs = jax.lax.scan(backward, jnp.zeros_like(m0), (xp, Pp, K, W, H), reverse=True)
    return xs, acc
