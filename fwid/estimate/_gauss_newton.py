"""Output-error Gauss-Newton with R relaxed at every step, built from optimistix's parts."""

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx
from jax import lax
from jaxtyping import Array, PyTree, Scalar

from ._prior import PriorBounds


# --------------------------------------------------------------------------------------------
# Gauss-Newton on the output-error likelihood with R relaxed at every step
# --------------------------------------------------------------------------------------------
def noise_covariance(v, N, diagonal: bool, floor):
    """Eq. (11): `R = 1/N sum_k v_k v_k^T` (or its diagonal) plus a tiny floor (invertible)."""
    vv = v.reshape(-1, v.shape[-1])
    R = vv.T @ vv / N
    if diagonal:
        R = jnp.diag(jnp.diag(R))
    return R + jnp.diag(floor)


def ml_cost(R, N, ny):
    """Eq. (10) with R from Eq. (11): `N ny / 2 + N/2 ln det R + N ny / 2 ln 2 pi`."""
    _, logdet = jnp.linalg.slogdet(R)
    return 0.5 * N * ny + 0.5 * N * logdet + 0.5 * N * ny * jnp.log(2 * jnp.pi)


class NoiseModel(eqx.Module):
    """The measurement-noise side of the output-error likelihood: R of Eq. (11) from the
    residuals `v` (`(..., ny)`, padded samples zero) and the cost of Eq. (10) at that R."""

    N: Array  # number of real samples
    floor: Array  # (ny,) added to R's diagonal so that it stays invertible
    diagonal: bool = eqx.field(static=True)

    @classmethod
    def of_data(cls, z, mask, diagonal: bool) -> "NoiseModel":
        """For measured outputs `z` (`(..., n, ny)`) with sample `mask` (`(..., n)`): N the
        real samples, and a floor of `(1e-9 x the outputs' RMS)^2` on R's diagonal."""
        N = jnp.sum(mask)
        zstd = jnp.sqrt(jnp.sum((z * mask[..., None]) ** 2, axis=tuple(range(z.ndim - 1))) / N)
        return cls(N=N, floor=(1e-9 * zstd + 1e-300) ** 2, diagonal=diagonal)

    def R(self, v):
        return noise_covariance(v, self.N, self.diagonal, self.floor)

    def cost(self, v):
        R = self.R(v)
        c = ml_cost(R, self.N, v.shape[-1])
        ok = jnp.isfinite(c) & jnp.all(jnp.isfinite(v))
        return jnp.where(ok, c, jnp.inf)

    def gradient_terms(self, v, J):
        """`(H, g)`: `sum_k J_k^T R^-1 J_k` and `sum_k J_k^T R^-1 v_k`, R at `v`. `J` is the
        residual Jacobian `(..., ny, p)`. `g` is the exact gradient of Eq. (10) with R from
        Eq. (11) (the `dR` terms cancel), `H` its Gauss-Newton Hessian."""
        ny = v.shape[-1]
        vv = v.reshape(-1, ny)
        JJ = J.reshape(vv.shape[0], ny, J.shape[-1])
        Rinv = jnp.linalg.inv(self.R(vv))
        return normal_equations(vv, JJ, Rinv)


def _normal_terms(vv, JJ, Rinv):
    """`sum_k J_k^T R^-1 J_k` and `sum_k J_k^T R^-1 v_k` of one fit: `vv` `(k, ny)`, `JJ`
    `(k, ny, p)`. Contracts J where it lies (whitening a transposed copy first is slower on
    XLA:CPU)."""
    H = jnp.einsum("kip,ij,kjq->pq", JJ, Rinv, JJ)
    g = jnp.einsum("kip,ij,kj->p", JJ, Rinv, vv)
    return H, g


@jax.custom_batching.custom_vmap
def normal_equations(vv, JJ, Rinv):
    """[`_normal_terms`][]; under `jax.vmap` (many fits in one call, `fit_each`) one fit after
    another (`lax.map`) instead of one batched contraction: a fit's Jacobian (460 kB for
    900 samples, 4 outputs, 16 parameters) stays in the cache while it is read twice, where
    the batched contraction streamed every fit's from memory (64 flights: 2.5-3x slower on a
    2-core CPU, `benchmarks/stages.py`). Each fit's numbers are those of the fit alone."""
    return _normal_terms(vv, JJ, Rinv)


@normal_equations.def_vmap
def _fit_by_fit(axis_size, in_batched, vv, JJ, Rinv):
    args = tuple(a if b else jnp.broadcast_to(a, (axis_size,) + a.shape)
                 for a, b in zip((vv, JJ, Rinv), in_batched))
    return lax.map(lambda a: _normal_terms(*a), args), (True, True)


def jacobian_once(
    residuals_and_jacobian: Callable[[Array], tuple[Array, Array]],
) -> Callable[[Array], Array]:
    """The residual function, with a forward-mode derivative that is the Jacobian computed
    once by `residuals_and_jacobian(theta) -> (r, dr/dtheta)` (shape `r.shape + (p,)`).

    `optimistix` linearises the residual function and then applies the linearisation to
    every basis vector (the Newton solve), and once more to the step (the line search). For
    a simulation inside a loop each of those re-runs the loop, primal included; here the
    linear map is the product with the precomputed Jacobian. Only the derivative in `theta`
    is defined (the function's closure is treated as constant)."""

    @jax.custom_jvp
    def fn(theta):
        return residuals_and_jacobian(theta)[0]

    @fn.defjvp
    def _jvp(primals, tangents):
        (theta,), (dtheta,) = primals, tangents
        r, J = residuals_and_jacobian(theta)
        return r, jnp.tensordot(J, dtheta, axes=1)

    return fn


class _RelaxedState(eqx.Module):
    step_size: Array
    cost: Array  # Eq. (10) at the last accepted point
    cost_prev: Array  # ... and at the one before it
    history: Array  # the cost after each accepted step
    accepted: Array  # accepted steps (the first evaluation, at the start, not counted)


class _RelaxedStepHalving(optx.AbstractSearch):
    """Step halving on the likelihood itself (Eq. 10 with R from Eq. 11 at the trial point):
    a step is accepted when it lowers the cost by at least `slope` times the first-order
    prediction (Armijo), otherwise halved. The cost includes the prior's
    (`fwid.estimate._prior`); with bounds the step is the projected one, so the halving
    searches along the projected path (Bertsekas' projected Newton). A step whose predicted decrease is below the
    cost's round-off (`roundoff (1 + |cost|)`) is accepted unless the cost rises by more than
    that. Keeps the cost history of the accepted points."""

    noise: NoiseModel
    prior: PriorBounds | None
    history_length: int = eqx.field(static=True)
    slope: float = 1e-4
    roundoff: float = 1e3 * float(jnp.finfo(jnp.float64).eps)

    def init(self, y, f_info_struct):
        del f_info_struct
        inf = jnp.array(jnp.inf, dtype=y.dtype)
        return _RelaxedState(step_size=jnp.array(1.0, dtype=y.dtype), cost=inf, cost_prev=inf,
                             history=jnp.full(self.history_length, jnp.nan, dtype=y.dtype),
                             accepted=jnp.array(0))

    def step(self, first_step, y, y_eval, f_info, f_eval_info, state):
        c_eval = self.noise.cost(f_eval_info.residual)
        v = f_info.residual
        Rinv = jnp.linalg.inv(self.noise.R(v))
        dv = f_info.jac.mv(y_eval - y)  # the residuals' first-order change
        predicted = jnp.einsum("...i,ij,...j->", v, Rinv, dv)  # gradient . step
        if self.prior is not None:  # its cost, and its gradient W^2 (y - mean) . step
            c_eval = c_eval + self.prior.cost(y_eval)
            w2 = self.prior.weight**2
            predicted = predicted + jnp.sum(w2 * (y - self.prior.mean) * (y_eval - y))
        armijo = (c_eval - state.cost <= self.slope * predicted) & (predicted <= 0)
        # Near the optimum the decrease a step promises falls below the cost's round-off,
        # where comparing costs decides nothing: then take the step unless the cost rises
        # by more than its round-off.
        noise = self.roundoff * (1.0 + jnp.abs(state.cost))
        negligible = (-predicted <= noise) & (c_eval - state.cost <= noise)
        accept = first_step | ((armijo | negligible) & jnp.isfinite(c_eval))
        counted = accept & ~first_step
        history = jnp.where(
            counted, state.history.at[state.accepted].set(c_eval, mode="drop"), state.history)
        new = _RelaxedState(
            step_size=jnp.where(accept, 1.0, 0.5 * state.step_size),
            cost=jnp.where(accept, c_eval, state.cost),
            cost_prev=jnp.where(accept, state.cost, state.cost_prev),
            history=history,
            accepted=state.accepted + counted.astype(state.accepted.dtype),
        )
        return new.step_size, accept, optx.RESULTS.successful, new


class _RelaxedNewtonState(eqx.Module):
    y: Array  # the point the step starts from
    newton: Array  # the step is clip(y - step_size * newton) - y
    sensitivity: Array  # sqrt(diag H): the whitened-residual norm per unit of each parameter
    decrement: Array  # g^T H^-1 g: twice the cost decrease the full step predicts
    held: Array  # -1 / +1: held at the lower / upper bound for this step, 0: free
    result: optx.RESULTS


def _scaled_newton(H, g, free):
    """`H^-1 g` over the `free` parameters (0 for the others), solved (Cholesky) after
    scaling every parameter to unit sensitivity."""
    h = jnp.sqrt(jnp.diag(H))
    d = jnp.where(free & (h > 0), 1.0 / jnp.where(h > 0, h, 1.0), 0.0)
    Hs = H * d[:, None] * d[None, :] + jnp.diag(jnp.where(d > 0, 0.0, 1.0))
    # Cholesky by hand rather than `lineax.linear_solve`: lineax compares the operand's
    # sharding with the operator's, which fails inside `shard_map` (one device's flights).
    factor = jax.scipy.linalg.cho_factor(Hs, lower=True)
    return d * jax.scipy.linalg.cho_solve(factor, d * g)


def bounded_newton(H, g, y, lower, upper):
    """The bounded-variable Gauss-Newton step (Jategaonkar 2015, Sec. 4.13.3): the Newton
    step `H^-1 g` (the step is its negative) with every parameter that sits at a bound and
    whose step points out of the bounds held there (step 0), the step recomputed for the
    others, until no held parameter's step would leave (at most `p` rounds: the held set
    only grows). Returns `(newton, held)`, `held` -1 / +1 at the lower / upper bound, else 0.
    Without bounds (or none reached) it is the plain Gauss-Newton step, bit for bit."""
    at_low, at_high = y <= lower, y >= upper

    def grow(carry):
        held, _ = carry
        n = _scaled_newton(H, g, ~held)
        new = held | (at_low & (n > 0)) | (at_high & (n < 0))
        return new, jnp.any(new != held)

    held, _ = jax.lax.while_loop(lambda c: c[1], grow,
                                 (jnp.zeros(y.shape, bool), jnp.any(at_low | at_high)))
    newton = _scaled_newton(H, g, ~held)
    side = jnp.where(held & at_low, -1, jnp.where(held & at_high, 1, 0))
    return newton, side


class _RelaxedNewtonDescent(optx.AbstractDescent):
    """Jategaonkar's Gauss-Newton step `(sum J^T R^-1 J + W^2) dtheta = -(sum J^T R^-1 v +
    W^2 (theta - mean))` with R from the residuals at the current point (`W`, `mean`: the
    prior's, zero without one), solved (Cholesky) on the 16x16-sized normal equations after
    scaling every parameter to unit sensitivity; with bounds, the bounded-variable step
    ([`bounded_newton`][]) projected into the bounds."""

    noise: NoiseModel
    prior: PriorBounds | None = None

    def init(self, y, f_info_struct):
        del f_info_struct
        return _RelaxedNewtonState(y=y, newton=jnp.zeros_like(y), sensitivity=jnp.ones_like(y),
                                   decrement=jnp.array(jnp.inf, dtype=y.dtype),
                                   held=jnp.zeros(y.shape, int),
                                   result=optx.RESULTS.successful)

    def query(self, y, f_info, state):
        del state
        v = f_info.residual
        J = f_info.jac.as_matrix().reshape(*v.shape, y.shape[0])
        H, g = self.noise.gradient_terms(v, J)
        if self.prior is None:
            newton, held = _scaled_newton(H, g, jnp.ones(y.shape, bool)), jnp.zeros(y.shape, int)
        else:
            H, g = self.prior.add_terms(H, g, y)
            newton, held = bounded_newton(H, g, y, self.prior.lower, self.prior.upper)
        ok = jnp.all(jnp.isfinite(newton))
        newton = jnp.where(ok, newton, 0.0)
        result = optx.RESULTS.where(ok, optx.RESULTS.successful,
                                    optx.RESULTS.promote(lx.RESULTS.singular))
        return _RelaxedNewtonState(y=y, newton=newton, sensitivity=jnp.sqrt(jnp.diag(H)),
                                   decrement=g @ newton, held=held, result=result)

    def step(self, step_size, state):
        if self.prior is None:
            return -step_size * state.newton, state.result
        y = state.y
        return self.prior.clip(y - step_size * state.newton) - y, state.result


class RelaxedGaussNewton(optx.AbstractGaussNewton):
    """Output-error maximum likelihood by Gauss-Newton with the noise covariance relaxed at
    every step (Jategaonkar's method), built from optimistix's parts.

    The residual function returns the raw output errors `v = z - y(theta)` (`(..., ny)`); at
    every accepted point R is re-estimated from them (Eq. 11), the step solves
    `(sum J^T R^-1 J) dtheta = -sum J^T R^-1 v`, and the step is halved until the likelihood
    itself (Eq. 10 at the trial point's own R) decreases. It stops at an accepted point where
    the next step is below `atol + rtol |theta|` for every parameter, measured in units of
    unit sensitivity (`theta_i sqrt(H_ii)`), and the cost has settled (its last change, or
    the decrease the next step predicts, below `cost_rtol (1 + |cost|)`); or after
    `stall_steps` halvings in a row (no step lowers the cost: converged to round-off).
    The relaxation converges linearly (here by a factor of about 40 per step), so a tight
    `atol` costs a step or two.

    With a `prior` (`fwid.estimate.PriorBounds`: a prior and bounds) its residuals
    `(theta - mean) / std` join the cost, the step and the convergence test, and the step is
    the bounded-variable one (`bounded_newton`), projected into the bounds.
    """

    rtol: float
    atol: float
    norm: Callable[[PyTree], Scalar]
    descent: _RelaxedNewtonDescent
    search: _RelaxedStepHalving
    verbose: Callable[..., None]
    cost_rtol: float
    stall_steps: int = eqx.field(static=True)

    def __init__(self, noise: NoiseModel, prior: PriorBounds | None = None, *,
                 rtol: float = 1e-10, atol: float = 1e-9, cost_rtol: float = 1e-10,
                 history_length: int = 60, stall_steps: int = 10):
        self.rtol = rtol
        self.atol = atol
        self.norm = optx.max_norm
        self.descent = _RelaxedNewtonDescent(noise, prior)
        self.search = _RelaxedStepHalving(noise, prior, history_length)
        self.verbose = lambda **kw: None
        self.cost_rtol = cost_rtol
        self.stall_steps = stall_steps

    def terminate(self, fn, y, args, options, state, tags):
        del fn, args, options, tags
        s, d = state.search_state, state.descent_state
        just_accepted = ~state.first_step & (state.num_steps_since_acceptance == 0) & (
            s.accepted > 0)
        tol = self.atol + self.rtol * jnp.abs(y) * d.sensitivity
        step_small = jnp.all(jnp.abs(d.newton) * d.sensitivity <= tol)
        cost_tol = self.cost_rtol * (1.0 + jnp.abs(s.cost))
        cost_small = (jnp.abs(s.cost_prev - s.cost) <= cost_tol) | (0.5 * d.decrement <= cost_tol)
        converged = just_accepted & step_small & cost_small
        stalled = state.num_steps_since_acceptance >= self.stall_steps
        return converged | stalled, state.result


class RelaxedSolution(eqx.Module):
    """What [`solve_relaxed`][] found: the estimate `theta`, the residuals `v` `(..., ny)` and
    their Jacobian `J` `(..., ny, p)` at it (the last accepted point), R of Eq. (11) at `v`,
    the cost (Eq. 10, plus the prior's part), the cost `history` of the accepted steps,
    `accepted` steps, `steps` taken, whether the solver `converged`, and which parameters
    the last step `held` at a bound (-1 lower, +1 upper, 0 free: the active bounds)."""

    theta: Array
    v: Array
    J: Array
    R: Array
    cost: Array
    history: Array
    accepted: Array
    steps: Array
    converged: Array
    held: Array

    def whitened(self) -> tuple[Array, Array]:
        """`(w, S)`: the residuals and their Jacobian whitened by R (`w = L^-1 v`,
        `S = L^-1 J`, `R = L L^T`), shapes as `v` and `J`; the Fisher information matrix is
        `sum S^T S` (Eq. 10's Gauss-Newton Hessian at the estimate)."""
        Linv = jnp.linalg.inv(jnp.linalg.cholesky(self.R))
        return self.v @ Linv.T, jnp.einsum("...ip,ji->...jp", self.J, Linv)


def solve_relaxed(
    residuals_and_jacobian: Callable[[Array], tuple[Array, Array]],
    theta0: Array,
    noise: NoiseModel,
    *,
    rtol: float,
    cost_rtol: float,
    max_steps: int,
    atol: float = 1e-9,
    prior: PriorBounds | None = None,
) -> RelaxedSolution:
    """Minimise the output-error likelihood (Eq. 10, R relaxed by Eq. 11 at every step) of
    the residuals `v(theta)` by [`RelaxedGaussNewton`][]: one `optimistix.least_squares` solve
    from `theta0`, the residuals and their Jacobian from `residuals_and_jacobian(theta) ->
    (v, dv/dtheta)` once per point ([`jacobian_once`][]). Pure and jit/vmap-able; shared by
    output error (`v` the output errors) and filter error (`v` the innovations, Jategaonkar
    Eq. 5.36 at a fixed gain). With a `prior` ([`PriorBounds`][]: a prior and bounds) the
    start is clipped into the bounds and the cost is the posterior's."""
    residuals = jacobian_once(residuals_and_jacobian)
    if prior is not None:
        theta0 = prior.clip(theta0)
    solver = RelaxedGaussNewton(noise, prior, rtol=rtol, atol=atol, cost_rtol=cost_rtol,
                                history_length=max_steps)
    sol = optx.least_squares(lambda th, _: residuals(th), solver, theta0, max_steps=max_steps,
                             throw=False)
    theta = sol.value
    state = sol.state
    v = state.f_info.residual
    J = state.f_info.jac.as_matrix().reshape(*v.shape, theta.shape[0])
    return RelaxedSolution(theta=theta, v=v, J=J, R=noise.R(v), cost=state.search_state.cost,
                           history=state.search_state.history,
                           accepted=state.search_state.accepted, steps=sol.stats["num_steps"],
                           converged=sol.result == optx.RESULTS.successful,
                           held=state.descent_state.held)
