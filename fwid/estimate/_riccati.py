"""The steady-state Kalman filter of the filter-error method, differentiable end to end.

Jategaonkar (2015), Sec. 5.3-5.5: for the linear (or linearised, Eqs. 5.50-5.51) system
`x' = A x + ... + F w` observed as `z = C x + ... + v`, with the innovation covariance `R`
estimated explicitly from the innovations (Eq. 5.40, the relaxation step), the steady-state
covariance `P` solves the Riccati equation of the book's Eq. (5.15),

    A P + P A^T - P C^T R^-1 C P / dt + F F^T = 0,                           (*)

and the gain is `K = P C^T R^-1` (Eq. 5.48). (*) is the continuous-time limit of the
discrete filter's Riccati equation with `R` as the innovation covariance
(`P = Phi (P - P C^T R^-1 C P) Phi^T + Q`, `Phi = I + A dt`, `Q = F F^T dt`); unlike that
discrete form, it has a stabilising solution for every `F` (the discrete fixed-`R` form has
none once `F` outgrows `R`, and the discrete form with `R` as the measurement noise gives
a different family of gains: on FVSysID TC04 `Cmq` 12.6 % from the book's filter-error
estimate instead of 2-3 %).

The primal is solved as the book does (Potter's method, Eqs. 5.16-5.17: the stable invariant
subspace of the Hamiltonian matrix), refined by Newton steps, without tracing derivatives;
the derivatives come from the implicit function theorem (`jax.custom_jvp`): the tangent
`dP` solves the Lyapunov equation `Acl dP + dP Acl^T = -(dA P + P dA^T - P dS P + d(FF^T))`
with `Acl = A - P S`, `S = C^T R^-1 C / dt`, an `nx^2 x nx^2` linear system. Gauss-Newton
Jacobians (forward mode) and gradients (reverse mode) therefore differentiate the Riccati
solution exactly, not an iteration.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

NEWTON_STEPS = 2


def _lyapunov_matrix(Acl):
    """The matrix of `X -> Acl X + X Acl^T` on `vec(X)` (row-major)."""
    eye = jnp.eye(Acl.shape[0], dtype=Acl.dtype)
    return jnp.kron(Acl, eye) + jnp.kron(eye, Acl)


def _potter(A, S, FF):
    """The stabilising solution of `A P + P A^T - P S P + FF = 0` from the Hamiltonian's
    stable invariant subspace (Eqs. 5.15-5.17), refined by Newton (Kleinman) steps."""
    n = A.shape[0]
    ham = jnp.block([[A.T, -S], [-FF, -A]])
    w, V = jnp.linalg.eig(ham)
    idx = jnp.argsort(jnp.real(w))[:n]  # the n eigenvalues with negative real parts
    U = V[:, idx]
    P = jnp.real(jnp.linalg.solve(U[:n].T, U[n:].T).T)  # U2 U1^-1
    P = 0.5 * (P + P.T)
    for _ in range(NEWTON_STEPS):
        G = A @ P + P @ A.T - P @ S @ P + FF
        dP = jnp.linalg.solve(_lyapunov_matrix(A - P @ S), -G.reshape(-1)).reshape(n, n)
        P = P + 0.5 * (dP + dP.T)
    return P


@jax.custom_jvp
def care(A: Float[Array, "nx nx"], S: Float[Array, "nx nx"], FF: Float[Array, "nx nx"]
         ) -> Float[Array, "nx nx"]:
    """The stabilising solution `P` of `A P + P A^T - P S P + FF = 0` (equation (*) of the
    module docstring with `S = C^T R^-1 C / dt`); differentiable by the implicit function
    theorem."""
    return _potter(A, S, FF)


@care.defjvp
def _care_jvp(primals, tangents):
    A, S, FF = primals
    dA, dS, dFF = tangents
    P = care(A, S, FF)
    n = P.shape[0]
    rhs = dA @ P + P @ dA.T - P @ dS @ P + dFF
    dP = jnp.linalg.solve(_lyapunov_matrix(A - P @ S), -rhs.reshape(-1)).reshape(n, n)
    return P, 0.5 * (dP + dP.T)


def discretise(A: Float[Array, "nx nx"], FF: Float[Array, "nx nx"], dt
               ) -> tuple[Float[Array, "nx nx"], Float[Array, "nx nx"]]:
    """`Phi = e^{A dt}` and the process-noise covariance of one sample interval,
    `Q = int_0^dt e^{A s} F F^T e^{A^T s} ds`, by Van Loan's matrix exponential (for
    simulating process noise)."""
    n = A.shape[0]
    M = jnp.block([[-A, FF], [jnp.zeros((n, n), dtype=A.dtype), A.T]]) * dt
    E = jax.scipy.linalg.expm(M)
    Phi = E[n:, n:].T
    Q = Phi @ E[:n, n:]
    return Phi, 0.5 * (Q + Q.T)


def steady_state_gain(A, C, FF, R, dt):
    """`(K, P)`: the steady-state Kalman gain `K = P C^T R^-1` (Eq. 5.48) and the covariance
    `P` of (*) (Eq. 5.15), for the state matrix `A`, the observation matrix `C`, `F F^T`, the
    innovation covariance `R` and the sample interval `dt`."""
    RinvC = jnp.linalg.solve(R, C)
    S = C.T @ RinvC / dt
    P = care(A, 0.5 * (S + S.T), FF)
    return P @ RinvC.T, P
