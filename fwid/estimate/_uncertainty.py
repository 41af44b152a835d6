"""Parameter uncertainty: Cramer-Rao bounds, and their correction for coloured residuals."""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float


def fisher_information(J: Float[Array, "k p"]) -> Float[Array, "p p"]:
    """`M = sum_k S_k^T R^-1 S_k` from the Jacobian of the *whitened* residuals."""
    return J.T @ J


def coloured_residual_middle(
    S: Float[Array, "n ny p"],
    v: Float[Array, "n ny"],
    mask: Float[Array, " n"],
    max_lag: int | Float[Array, ""] | None = None,
) -> Float[Array, "p p"]:
    """The middle term of Morelli and Klein's covariance for coloured residuals.

    `sum_i sum_j S_i^T C(j - i) S_j` for whitened sensitivities `S` and residuals `v`, where
    `C(tau) = w(tau) R_vv(tau)` and `R_vv(tau) = 1/N sum_k v_k v_{k+tau}^T` is the biased
    residual autocorrelation. With `max_lag=None` every lag counts with `w = 1` (Morelli and
    Klein's estimator); with a `max_lag` L, a Bartlett window `w = 1 - |tau|/(L + 1)` keeps
    the lags up to L. The window matters: at the estimate the residuals are orthogonal to the
    sensitivities, so the all-lag (raw periodogram) estimate has no residual power exactly
    where the sensitivities live and under-states the variance; the lag window smooths the
    residual spectrum across those frequencies. Computed in the frequency domain,
    `O(n log n)`, and positive semi-definite by construction (the Bartlett window has a
    non-negative spectrum). With white residuals it reduces to the Fisher information.
    """
    n, ny, _ = S.shape
    S = S * mask[:, None, None]
    v = v * mask[:, None]
    N = jnp.sum(mask)
    nfft = 2 * n
    Fv = jnp.fft.rfft(v, n=nfft, axis=0)  # (f, ny)
    # R_vv(tau) for tau = 0..n-1 (and negative lags by symmetry), all output pairs
    Rv = jnp.fft.irfft(jnp.conj(Fv)[:, :, None] * Fv[:, None, :], n=nfft, axis=0) / N
    tau = jnp.fft.fftfreq(nfft, 1.0 / nfft)  # circular lag index: 0, 1, .., -1
    if max_lag is not None:
        w = jnp.clip(1.0 - jnp.abs(tau) / (max_lag + 1.0), 0.0, None)
        Rv = Rv * w[:, None, None]
    Pv = jnp.fft.rfft(Rv, axis=0)  # (f, ny, ny): the (windowed) residual cross-spectrum
    FS = jnp.fft.rfft(S, n=nfft, axis=0)  # (f, ny, p)
    weights = jnp.full(Pv.shape[0], 2.0).at[0].set(1.0).at[-1].set(1.0)  # rfft half-spectrum
    mid = jnp.einsum("f,fap,fab,fbq->pq", weights, FS, Pv, jnp.conj(FS)) / nfft
    return jnp.real(mid)


def correlation_length(v: Float[Array, "n ny"], mask: Float[Array, " n"], level: float = 0.05):
    """The first lag at which the mean normalised autocorrelation of `v` drops below `level`."""
    n = v.shape[0]
    v = v * mask[:, None]
    F = jnp.fft.rfft(v, n=2 * n, axis=0)
    r = jnp.fft.irfft(jnp.abs(F) ** 2, n=2 * n, axis=0)[:n]  # (n, ny)
    rho = jnp.mean(r / jnp.maximum(r[:1], 1e-300), axis=1)
    return jnp.argmax(rho < level)


def lag1_autocorrelation(v: Float[Array, "n ny"], mask: Float[Array, " n"]
                         ) -> Float[Array, " ny"]:
    """Each output's residual autocorrelation at one sample, `sum v_k v_k+1 / sum v_k^2`
    (padding excluded): about 0 (within `2/sqrt(n)`) for white measurement noise, near 1
    when model error or process noise dominates the residuals."""
    v = v * mask[:, None]
    both = (mask[1:] * mask[:-1])[:, None]
    return jnp.sum(v[1:] * v[:-1] * both, axis=0) / jnp.maximum(jnp.sum(v**2, axis=0), 1e-300)


def covariance(M, middle=None):
    """`M^-1` (Cramer-Rao), or `M^-1 middle M^-1` (corrected for coloured residuals)."""
    Minv = jnp.linalg.inv(M)
    if middle is None:
        return Minv
    return Minv @ middle @ Minv


def covariance_held(M, middle=None, held=None):
    """[`covariance`][] of the parameters free at a bound-constrained estimate: those that
    sit at an active bound (`held != 0`, see `fwid.estimate._gauss_newton.bounded_newton`)
    are taken as known there (the information of the others is `M` without their rows and
    columns: the conditional covariance, the uncertainty of the others given the held ones
    at their bounds), and their own rows and columns are NaN. An estimate at an active bound
    is where the likelihood's maximum inside the bounds is, not a stationary point: the
    curvature there does not give its spread (which is one-sided), so none is reported.
    With nothing held this is [`covariance`][], bit for bit."""
    if held is None:
        return covariance(M, middle)
    free = held == 0
    both = free[:, None] & free[None, :]
    eye = jnp.eye(M.shape[0], dtype=M.dtype)
    cov = covariance(jnp.where(both, M, eye),
                     None if middle is None else jnp.where(both, middle, 0.0))
    return jnp.where(both, cov, jnp.nan)


#: A covariance whose correlation form leaves [-1, 1] by more than this is not positive
#: semi-definite: it came from an information matrix that is singular to working precision.
CORR_TOLERANCE = 1e-6


def correlation(cov: Float[Array, "p p"]) -> Float[Array, "p p"]:
    """The correlation matrix of a covariance, always within [-1, 1].

    A covariance inverted from a numerically singular information matrix need not be
    positive semi-definite, and its "correlations" then leave [-1, 1] (+7.2 and -5.0 on a
    hostile flight): no correlation of the estimates exists there. Such a matrix gives NaN
    throughout (the fit's warnings then name the parameters the information cannot
    separate, `fwid.estimate._warnings`); otherwise rounding beyond +-1 is clipped. Rows of
    parameters without a variance (NaN, e.g. held at an active bound) stay NaN and do not
    count against the others."""
    d = jnp.sqrt(jnp.diag(cov))
    c = cov / jnp.outer(d, d)
    beyond = jnp.any(jnp.where(jnp.isfinite(c), jnp.abs(c), 0.0) > 1.0 + CORR_TOLERANCE)
    return jnp.where(beyond, jnp.nan, jnp.clip(c, -1.0, 1.0))
