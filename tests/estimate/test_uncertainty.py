"""The coloured-residual middle term (Morelli and Klein) against naive double sums."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.estimate import coloured_residual_middle, correlation


def _rvv(v, tau):
    """Biased residual autocorrelation R_vv(tau) = 1/N sum_k v_k v_{k+tau}^T (all lags)."""
    n, ny = v.shape
    out = np.zeros((ny, ny))
    for k in range(n):
        if 0 <= k + tau < n:
            out += np.outer(v[k], v[k + tau])
    return out / n


def _naive(S, v, weight=lambda tau: 1.0, order="j-i"):
    """sum_i sum_j S_i^T w(tau) R_vv(tau) S_j with tau = j - i (i.e. E[v_i v_j^T])."""
    n = S.shape[0]
    total = np.zeros((S.shape[2], S.shape[2]))
    for i in range(n):
        for j in range(n):
            tau = j - i if order == "j-i" else i - j
            total += weight(tau) * S[i].T @ _rvv(v, tau) @ S[j]
    return total


def _middle(S, v, mask=None, max_lag=None):
    mask = jnp.ones(S.shape[0]) if mask is None else jnp.asarray(mask)
    return np.asarray(coloured_residual_middle(jnp.asarray(S), jnp.asarray(v), mask, max_lag))


@pytest.fixture(scope="module")
def sv():
    rng = np.random.default_rng(3)
    n, ny, p = 9, 3, 4
    S = rng.standard_normal((n, ny, p))
    # coloured, cross-correlated residuals so that every lag and output pair matters
    e = rng.standard_normal((n + 2, ny))
    v = e[2:] + 0.6 * e[1:-1] @ rng.standard_normal((ny, ny)) + 0.3 * e[:-2]
    return S, v


def test_all_lags_equals_naive_double_sum(sv):
    S, v = sv
    got = _middle(S, v)
    ref = _naive(S, v)
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(got, got.T, rtol=0, atol=1e-12)
    # the lag ordering matters with several outputs: the transposed convention differs
    assert not np.allclose(_naive(S, v, order="i-j"), ref, rtol=1e-3)


@pytest.mark.parametrize("L", [0, 1, 3])
def test_bartlett_window_equals_naive_weighted_sum(sv, L):
    S, v = sv
    got = _middle(S, v, max_lag=L)
    ref = _naive(S, v, weight=lambda tau: max(0.0, 1.0 - abs(tau) / (L + 1.0)))
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10)


def test_positive_semidefinite(sv):
    S, v = sv
    for L in (None, 2):
        ev = np.linalg.eigvalsh(_middle(S, v, max_lag=L))
        assert ev.min() > -1e-10 * ev.max(), ev


def test_white_expectation_is_fisher_information_exactly(sv):
    """The middle term is a quadratic form Q(v); for white v (unit covariance)
    E[Q(v)] = sum_m Q(e_m) over the unit vectors, which must equal S^T S."""
    S, _ = sv
    n, ny, p = S.shape
    basis = jnp.eye(n * ny).reshape(n * ny, n, ny)
    fisher = np.einsum("iap,iaq->pq", S, S)
    for L in (None, 2):
        q = jax.vmap(lambda e: coloured_residual_middle(jnp.asarray(S), e, jnp.ones(n), L))(basis)
        np.testing.assert_allclose(np.asarray(q).sum(0), fisher, rtol=1e-10, atol=1e-10)


def test_white_monte_carlo_close_to_fisher_information():
    rng = np.random.default_rng(11)
    n, ny, p, draws = 64, 2, 3, 2000
    S = rng.standard_normal((n, ny, p))
    V = rng.standard_normal((draws, n, ny))
    mids = jax.vmap(lambda v: coloured_residual_middle(jnp.asarray(S), v, jnp.ones(n)))(
        jnp.asarray(V))
    mean = np.asarray(mids).mean(0)
    fisher = np.einsum("iap,iaq->pq", S, S)
    np.testing.assert_allclose(np.diag(mean), np.diag(fisher), rtol=0.1)
    scale = np.sqrt(np.outer(np.diag(fisher), np.diag(fisher)))
    assert np.all(np.abs(mean - fisher) < 0.1 * scale)


def test_expectation_for_cross_lagged_noise_uses_e_vi_vj():
    """Output 1 is output 0 delayed by one sample: E[v_i v_j^T] is not symmetric in i, j.

    The expected all-lag middle term is sum_ij S_i^T C(j - i) S_j (n - |i - j|) / n with
    C(tau) = E[v_k v_{k+tau}^T] (the Bartlett taper of the biased estimator)."""
    rng = np.random.default_rng(5)
    n, p = 12, 3
    S = rng.standard_normal((n, 2, p))
    # v_k = (e_{k+1}, e_k): a linear map of n + 1 white samples
    Lmap = np.zeros((n + 1, n, 2))
    for k in range(n):
        Lmap[k + 1, k, 0] = 1.0
        Lmap[k, k, 1] = 1.0
    q = jax.vmap(lambda v: coloured_residual_middle(jnp.asarray(S), v, jnp.ones(n)))(
        jnp.asarray(Lmap))
    expected_q = np.asarray(q).sum(0)
    C = {0: np.eye(2), 1: np.array([[0.0, 1.0], [0.0, 0.0]]), -1: np.array([[0.0, 0.0], [1.0, 0.0]])}
    ref = np.zeros((p, p))
    for i in range(n):
        for j in range(n):
            if abs(j - i) <= 1:
                ref += S[i].T @ C[j - i] @ S[j] * (n - abs(i - j)) / n
    np.testing.assert_allclose(expected_q, ref, rtol=1e-10, atol=1e-10)


def test_mask_zeroes_padding(sv):
    S, v = sv
    n, ny, p = S.shape
    rng = np.random.default_rng(9)
    k = 5
    Sp = np.concatenate([S, 1e3 * rng.standard_normal((k, ny, p))])
    vp = np.concatenate([v, 1e3 * rng.standard_normal((k, ny))])
    mask = np.r_[np.ones(n), np.zeros(k)]
    for L in (None, 2):
        np.testing.assert_allclose(_middle(Sp, vp, mask, L), _middle(S, v, max_lag=L),
                                   rtol=1e-10, atol=1e-9)


def test_correlation_matrix():
    rng = np.random.default_rng(2)
    A = rng.standard_normal((5, 3))
    cov = A.T @ A
    corr = np.asarray(correlation(jnp.asarray(cov)))
    d = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(corr, cov / np.outer(d, d), rtol=1e-12)
    np.testing.assert_allclose(np.diag(corr), 1.0, rtol=1e-12)
