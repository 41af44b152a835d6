"""The smoother's means equal the batch solution of the same linear-Gaussian problem
(weighted least squares over the whole trajectory), with missing measurements, two
measurements per step, known inputs and several data columns."""

import jax.numpy as jnp
import numpy as np

from fwid.reconstruction import _model as mdl
from fwid.reconstruction._kalman import smooth


def test_smoother_equals_batch_least_squares():
    N, dt, rng = 120, 0.005, np.random.default_rng(0)
    F, Q = mdl.transition(dt, False), mdl.process_noise(dt, 1e3, 1e5, False)
    n = F.shape[0]
    H = rng.standard_normal((N, 2, n))
    R = np.array([1.0, 4.0])
    z = rng.standard_normal((N, 2, 3))
    mask = rng.random((N, 2)) > 0.2
    u = 0.01 * rng.standard_normal((N, n, 3))
    m0, P0 = np.zeros((n, 3)), 10 * np.eye(n)
    xs, _ = smooth(*(jnp.asarray(a) for a in (F, Q, H, R, z, mask, u, m0, P0)))

    def whiten(C):
        w, V = np.linalg.eigh(C)
        return (V / np.sqrt(w)).T

    blocks, rhs = [], []
    e = np.zeros((n, N * n))
    e[:, :n] = np.eye(n)
    blocks.append(whiten(P0) @ e)
    rhs.append(whiten(P0) @ m0)
    Wq = whiten(Q)
    for k in range(N - 1):
        e = np.zeros((n, N * n))
        e[:, (k + 1) * n:(k + 2) * n], e[:, k * n:(k + 1) * n] = np.eye(n), -F
        blocks.append(Wq @ e)
        rhs.append(Wq @ u[k])
    for k in range(N):
        for i in range(2):
            if mask[k, i]:
                e = np.zeros((1, N * n))
                e[0, k * n:(k + 1) * n] = H[k, i] / np.sqrt(R[i])
                blocks.append(e)
                rhs.append(z[k, i][None] / np.sqrt(R[i]))
    ref = np.linalg.lstsq(np.vstack(blocks), np.vstack(rhs), rcond=None)[0].reshape(N, n, 3)
    assert np.max(np.abs(np.asarray(xs) - ref)) < 1e-8 * np.max(np.abs(ref))
