"""The steady-state Kalman filter of the filter-error method, differentiable end to end.

Jategaonkar (2015), Sec. 5.3-5.5: for the linear (or linearised, Eqs. 5.50-5.51) system

    x_{k+1} = Phi x_k + ... + w_k,  cov(w) = Q = int_0^dt e^{A s} F F^T e^{A^T s} ds
    z_k     = C x_k + ... + v_k

with the innovation covariance `R` estimated explicitly from the innovations (Eq. 5.40, the
relaxation step), the steady-state prediction-error covariance `P` solves the Riccati equation
in the form with `R` fixed,

    P = Phi (P - P C^T R^-1 C P) Phi^T + Q,                                   (*)

and the gain is `K = P C^T R^-1` (Eq. 5.48). (*) is the discrete-time counterpart of the
book's Eq. (5.15) `A P + P A^T - P C^T R^-1 C P / dt + F F^T = 0` (Potter's method), to which
it reduces for `Phi = I + A dt`, `Q = F F^T dt`; the implied measurement-noise covariance is
`R - C P C^T` (it must stay positive: the book's constraint on `KC`, Sec. 5.5.3).

(*) is solved by fixed-point iterations (the filter's own covariance recursion, from `Q`)
followed by Newton steps, all without tracing derivatives; the derivatives come from the
implicit function theorem (`jax.custom_jvp`): with `G(P) = Phi (P - P S P) Phi^T + Q - P`,
`S = C^T R^-1 C`, the tangent `dP` solves the linear equation `G_P[dP] = -dG`, an
`nx^2 x nx^2` system. Gauss-Newton Jacobians (forward mode) and gradients (reverse mode)
therefore differentiate through the Riccati solution exactly, not through the iterations.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

FIXED_POINT_ITERATIONS = 60
NEWTON_ITERATIONS = 12


def _residual(P, Phi, S, Q):
    return Phi @ (P - P @ S @ P) @ Phi.T + Q - P


def _newton_matrix(P, Phi, S):
    """The matrix of the linear map `X -> G_P[X] = Phi (X - X S P - P S X) Phi^T - X` on
    `vec(X)` (row-major)."""
    n = P.shape[0]
    eye = jnp.eye(n * n, dtype=P.dtype).reshape(n * n, n, n)
    cols = jax.vmap(lambda X: (Phi @ (X - X @ S @ P - P @ S @ X) @ Phi.T - X).reshape(-1))(eye)
    return cols.T


def _solve(Phi, S, Q):
    def fixed_point(P, _):
        P = Phi @ (P - P @ S @ P) @ Phi.T + Q  # the filter's covariance recursion
        return 0.5 * (P + P.T), None

    P, _ = jax.lax.scan(fixed_point, Q, None, length=FIXED_POINT_ITERATIONS)

    def newton(P, _):
        G = _residual(P, Phi, S, Q)
        dP = jnp.linalg.solve(_newton_matrix(P, Phi, S), -G.reshape(-1)).reshape(P.shape)
        P = P + dP
        return 0.5 * (P + P.T), None

    P, _ = jax.lax.scan(newton, P, None, length=NEWTON_ITERATIONS)
    return P


@jax.custom_jvp
def riccati_fixed_r(Phi: Float[Array, "nx nx"], S: Float[Array, "nx nx"],
                    Q: Float[Array, "nx nx"]) -> Float[Array, "nx nx"]:
    """The stabilising solution `P` of `P = Phi (P - P S P) Phi^T + Q` (equation (*) of the
    module docstring with `S = C^T R^-1 C`); differentiable by the implicit function theorem."""
    return _solve(Phi, S, Q)


@riccati_fixed_r.defjvp
def _riccati_jvp(primals, tangents):
    Phi, S, Q = primals
    dPhi, dS, dQ = tangents
    P = riccati_fixed_r(Phi, S, Q)
    M = P - P @ S @ P
    dG = dPhi @ M @ Phi.T + Phi @ M @ dPhi.T - Phi @ P @ dS @ P @ Phi.T + dQ
    dP = jnp.linalg.solve(_newton_matrix(P, Phi, S), -dG.reshape(-1)).reshape(P.shape)
    return P, 0.5 * (dP + dP.T)


def discretise(A: Float[Array, "nx nx"], FF: Float[Array, "nx nx"], dt
               ) -> tuple[Float[Array, "nx nx"], Float[Array, "nx nx"]]:
    """`Phi = e^{A dt}` and the process-noise covariance of one sample interval,
    `Q = int_0^dt e^{A s} F F^T e^{A^T s} ds`, by Van Loan's matrix exponential."""
    n = A.shape[0]
    M = jnp.block([[-A, FF], [jnp.zeros((n, n), dtype=A.dtype), A.T]]) * dt
    E = jax.scipy.linalg.expm(M)
    Phi = E[n:, n:].T
    Q = Phi @ E[:n, n:]
    return Phi, 0.5 * (Q + Q.T)


def steady_state_gain(A, C, FF, R, dt):
    """`(K, P)`: the steady-state Kalman gain `K = P C^T R^-1` (Eq. 5.48) and the prediction
    covariance `P` of (*), for the continuous state matrix `A`, the observation matrix `C`,
    `F F^T`, the innovation covariance `R` and the sample interval `dt`."""
    Phi, Q = discretise(A, FF, dt)
    Rinv = jnp.linalg.inv(R)
    S = C.T @ Rinv @ C
    P = riccati_fixed_r(Phi, 0.5 * (S + S.T), Q)
    return P @ C.T @ Rinv, P
