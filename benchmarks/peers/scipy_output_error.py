"""Plain numpy/scipy output-error ML estimator: the independent reference and speed baseline.

This is what a Python user would write to do output-error maximum-likelihood estimation
without fwid, and nothing cleverer:

* simulation: a fixed-step classical RK4 loop in numpy, step = data step, the input taken at
  the start and end of each step and linearly interpolated at the half step;
* cost: Eq. (10) of the paper (negative log-likelihood with Gaussian measurement noise) with
  R from Eq. (11) (covariance of the output residuals);
* relaxation: fix R, minimise over theta with ``scipy.optimize.least_squares`` on the
  whitened residuals (finite-difference Jacobian), update R from the new residuals, repeat
  until the relative change in the cost is below ``rtol`` (1e-6);
* Cramer-Rao standard deviations from the final Jacobian:
  F = sum_k J_k^T R^-1 J_k, std = sqrt(diag F^-1).

Several experiments (manoeuvres) are fitted jointly: one parameter vector, one R pooled over
all samples, each experiment integrated from its own (fixed) initial state.

No JAX here on purpose: it must stay independent of fwid.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import least_squares

__all__ = ["rk4_simulate", "fit_output_error", "nll_cost"]


def rk4_simulate(f, theta, t, u, x0):
    """Integrate x' = f(x, u, theta) over the sample times ``t`` with fixed-step RK4.

    ``t`` (N,), ``u`` (N, nu) or (N,), ``x0`` (nx,).  The step is t[k+1]-t[k]; the input is
    u[k] at the start of the step, u[k+1] at the end and their mean at the half step.
    Returns the states at the sample times, shape (N, nx), with X[0] = x0.

    Batched: with ``x0`` of shape (P, nx) (and an ``f`` that broadcasts over the leading
    axis, e.g. P parameter sets at once) it returns (N, P, nx).
    """
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    if u.ndim == 1:
        u = u[:, None]
    x = np.array(x0, dtype=float)
    n = t.shape[0]
    X = np.empty((n, *x.shape))
    X[0] = x
    for k in range(n - 1):
        h = t[k + 1] - t[k]
        u1 = u[k]
        u2 = u[k + 1]
        um = 0.5 * (u1 + u2)
        k1 = f(x, u1, theta)
        k2 = f(x + 0.5 * h * k1, um, theta)
        k3 = f(x + 0.5 * h * k2, um, theta)
        k4 = f(x + h * k3, u2, theta)
        x = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        X[k + 1] = x
    return X


def _outputs(f, h, theta, t, u, x0):
    X = rk4_simulate(f, theta, t, u, x0)
    if h is None:
        return X
    uu = np.asarray(u, dtype=float)
    if uu.ndim == 1:
        uu = uu[:, None]
    return np.array([h(X[k], uu[k], theta) for k in range(X.shape[0])])


def nll_cost(R, n_samples):
    """Eq. (10) evaluated at R = Eq. (11): N/2 ln det R + N ny/2 (1 + ln 2 pi)."""
    ny = R.shape[0]
    _, logdet = np.linalg.slogdet(R)
    return 0.5 * n_samples * logdet + 0.5 * n_samples * ny * (1.0 + np.log(2.0 * np.pi))


def _covariance(E, diag_R):
    R = E.T @ E / E.shape[0]
    if diag_R:
        R = np.diag(np.diag(R))
    return R


def fit_output_error(
    f,
    theta0,
    t_list,
    u_list,
    z_list,
    x0_list,
    *,
    h=None,
    free=None,
    diag_R=False,
    rtol=1e-6,
    max_outer=50,
    method="trf",
    verbose=False,
    batch=None,
):
    """Output-error ML fit of ``theta`` to one or more experiments.

    Parameters
    ----------
    f : callable f(x, u, theta) -> xdot (numpy arrays, one sample).
    theta0 : starting parameter vector (also supplies the values of fixed parameters).
    t_list, u_list, z_list, x0_list : per experiment: times (N,), inputs (N, nu), measured
        outputs (N, ny) and the initial state (nx,) the experiment is integrated from.
    h : optional output function h(x, u, theta) -> y; default y = x.
    free : optional boolean mask or index list of the parameters to estimate (default: all).
    diag_R : if True, keep only the diagonal of Eq. (11) (as Jategaonkar's ml_oem does);
        default False: the full residual covariance of Eq. (11).
    rtol : stop when the relative change of the cost between relaxation steps is below this.
    method : scipy least_squares method ('trf' or 'lm').
    batch : optional ``batch(thetas) -> Y``: the outputs of all experiments, concatenated in
        time, for P full parameter vectors at once, ``thetas`` (P, n_par) -> (P, N, ny). When
        given it replaces ``f``, ``h``, ``t_list``, ``u_list`` and ``x0_list`` (pass ``None``
        for those), and the forward-difference Jacobian (step ``sqrt(eps) max(1, |p|)``,
        scipy's) costs one batched simulation instead of one per parameter.

    Returns
    -------
    dict with theta (full vector), std (Cramer-Rao, 0 for fixed parameters), R, cost
    (Eq. 10 at the returned theta and R), n_iter (relaxation steps), n_fev (model
    simulations of all experiments, finite-difference ones included), n_nfev_inner
    (least_squares' own nfev), wall_s, converged, plus cost_history.
    """
    t_wall = time.perf_counter()
    theta0 = np.asarray(theta0, dtype=float)
    n_par = theta0.shape[0]
    if free is None:
        idx = np.arange(n_par)
    else:
        free = np.asarray(free)
        idx = np.flatnonzero(free) if free.dtype == bool else free.astype(int)
    if batch is None:
        data = [
            (np.asarray(t, float), np.asarray(u, float), np.asarray(z, float),
             np.asarray(x0, float))
            for t, u, z, x0 in zip(t_list, u_list, z_list, x0_list)
        ]
    z_all = np.concatenate([np.asarray(z, float) for z in z_list], axis=0)
    n_samples = z_all.shape[0]

    counter = {"sims": 0}

    def full_theta(p):
        th = theta0.copy()
        th[idx] = p
        return th

    def residual_matrix(p):
        th = full_theta(p)
        counter["sims"] += 1
        if batch is not None:
            return z_all - batch(th[None])[0]
        Y = np.concatenate([_outputs(f, h, th, t, u, x0) for t, u, _, x0 in data], axis=0)
        return z_all - Y

    def batched_jacobian(p, L_inv):
        """d(whitened residual)/dp by forward differences, all parameters in one call."""
        steps = np.sqrt(np.finfo(float).eps) * np.maximum(1.0, np.abs(p))
        P = np.repeat(full_theta(p)[None], len(idx) + 1, axis=0)
        P[np.arange(1, len(idx) + 1), idx] += steps
        counter["sims"] += len(idx) + 1
        Y = batch(P)
        dE = -(Y[1:] - Y[0]) / steps[:, None, None]  # (p, N, ny)
        return np.einsum("pkj,ij->kip", dE, L_inv).reshape(-1, len(idx))

    p = theta0[idx].copy()
    E = residual_matrix(p)
    R = _covariance(E, diag_R)
    cost = nll_cost(R, n_samples)
    history = [cost]
    n_inner = 0
    converged = False
    res = None
    L_inv = None
    n_outer = 0
    for n_outer in range(1, max_outer + 1):
        L = np.linalg.cholesky(R)
        L_inv = np.linalg.inv(L)

        def whitened(p_, L_inv=L_inv):
            E_ = residual_matrix(p_)
            if not np.all(np.isfinite(E_)):
                return np.full(E_.size, 1e10)
            return (E_ @ L_inv.T).ravel()

        jac = "2-point" if batch is None else (lambda p_, L_inv=L_inv: batched_jacobian(p_, L_inv))
        res = least_squares(whitened, p, method=method, jac=jac)
        n_inner += res.nfev
        p = res.x
        E = residual_matrix(p)
        R_used = R
        R = _covariance(E, diag_R)
        new_cost = nll_cost(R, n_samples)
        history.append(new_cost)
        if verbose:
            print(f"relaxation {n_outer}: cost {new_cost:.8g}, inner nfev {res.nfev}")
        if abs(new_cost - cost) <= rtol * abs(new_cost):
            converged = True
            cost = new_cost
            break
        cost = new_cost

    # Cramer-Rao bound. res.jac is d(whitened residual)/dp = -L^-1 dY/dp with R = R_used,
    # so J^T J = sum_k dy_k^T R_used^-1 dy_k. Re-weight to the final R (identical at
    # convergence to within the relaxation tolerance).
    J_w = res.jac
    L_used = np.linalg.cholesky(R_used)
    ny = R.shape[0]
    # unwhiten: rows of J_w come in blocks of ny per sample
    dY = -(J_w.reshape(n_samples, ny, -1))
    dY = np.einsum("ij,kjp->kip", L_used, dY)
    R_inv = np.linalg.inv(R)
    F = np.einsum("kip,ij,kjq->pq", dY, R_inv, dY)
    std_free = np.sqrt(np.diag(np.linalg.inv(F)))
    std = np.zeros(n_par)
    std[idx] = std_free
    return {
        "theta": full_theta(p),
        "std": std,
        "R": R,
        "cost": cost,
        "n_iter": n_outer,
        "n_fev": counter["sims"],
        "n_nfev_inner": n_inner,
        "converged": converged,
        "cost_history": history,
        "fisher": F,
        "wall_s": time.perf_counter() - t_wall,
    }


def batch_of(xdot, obs, names, t_list, u_list, x0_list, consts_list=None):
    """The ``batch`` argument of [`fit_output_error`][] for a model written once for numpy
    and JAX alike: ``xdot(x, u, p, c, xp)`` and ``obs(x, u, p, c, xp)`` index the state and
    input components with ``x[..., i]`` and return ``xp.stack([...], axis=-1)``; ``p`` maps
    ``names`` to values, here arrays over the P parameter vectors. RK4 as
    [`rk4_simulate`][], all P vectors in one loop over the samples."""
    consts_list = consts_list or [{} for _ in t_list]

    def batch(thetas):
        p = {k: thetas[:, i] for i, k in enumerate(names)}
        out = []
        for t, u, x0, c in zip(t_list, u_list, x0_list, consts_list):
            u = np.asarray(u, float).reshape(len(t), -1)
            x0s = np.broadcast_to(np.asarray(x0, float), (thetas.shape[0], len(x0)))
            X = rk4_simulate(lambda x, uu, _: xdot(x, uu, p, c, np), None, t, u, x0s)
            out.append(obs(X, u[:, None, :], p, c, np))  # (N, P, ny)
        return np.concatenate(out, axis=0).transpose(1, 0, 2)

    return batch
