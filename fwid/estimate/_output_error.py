"""Output-error maximum likelihood estimation, Eqs. (10)-(11), minimised by Gauss-Newton."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._errors import FitDivergedError
from ..models._greybox import GreyBoxModel
from ..simulation._buckets import bucket_length, pad_experiment
from ..simulation._experiment import Experiment, stack_experiments
from ..simulation._simulate import simulate, simulate_sensitivities
from . import _exported as exported
from .._advice import advise
from ._colour import colour_at_bandwidth
from ._gauss_newton import NoiseModel, solve_relaxed
from ._noise import check_noise, fall_back
from ._prior import PriorBounds, has_any, prior_bounds
from ._problem import (
    FitResult,
    check_information,
    flight_columns,
    flight_params,
    free_layout,
    merge_batch,
    prepare,
)
from ._stability import instability_warning
from ._uncertainty import (
    coloured_residual_middle,
    correlation,
    correlation_length,
    covariance_held,
    lag1_autocorrelation,
    fisher_information,
)
from ._warnings import fit_warnings, issue

# The Bartlett lag window of the coloured-residual bounds spans this many residual
# correlation lengths (see `benchmarks/calibration.py` for how it was chosen).
LAG_WINDOW_FACTOR = 4


def _simulate_batch(model, params, batch: Experiment):
    """Simulate every experiment of a batch; `params` values are scalars or `(B,)` arrays."""
    B = batch.t.shape[0]
    pb = {k: jnp.broadcast_to(v, (B,)) for k, v in params.items()}
    return jax.vmap(lambda e, p: simulate(model, e, p)[1])(batch, pb)


def raw_residuals(model, params, batch):
    y = _simulate_batch(model, params, batch)
    return (batch.z - y) * batch.mask[..., None]


def residuals_with_jacobian(model: GreyBoxModel, batch: Experiment, n_local_batch: int = 0,
                            paired: bool = False):
    """The function `theta -> (residuals, d residuals / d theta)` of a (padded) batch of
    experiments, `(B, n, ny)` and `(B, n, ny, p)`, masked, from one RK4 solve per experiment
    of its state and forward sensitivities ([`simulate_sensitivities`][]). In a joint fit
    (`n_local_batch` flights, each with its own local parameters) each flight's sensitivities
    are integrated for the global parameters and its own locals only (`flight_columns`): its
    row of the Jacobian is zero for the other flights' locals, so the cost does not grow with
    the number of flights squared."""

    def residuals_and_jacobian(theta):
        def one(e, b):
            if n_local_batch == 0:
                def params_of(th):
                    return flight_params(merge_batch(model, th, 0), b)
                return simulate_sensitivities(model, e, params_of, theta, paired=paired)
            # flight b depends on the global parameters and its own locals only: its
            # sensitivities are integrated for those, the rest of its row is zero
            own = flight_columns(model, n_local_batch, b)

            def params_of(th_own):
                return flight_params(merge_batch(model, theta.at[own].set(th_own),
                                                 n_local_batch), b)
            ys, dys_own = simulate_sensitivities(model, e, params_of, theta[own],
                                                 paired=paired)
            full = jnp.zeros(dys_own.shape[:-1] + theta.shape, dys_own.dtype)
            return ys, full.at[..., own].set(dys_own)

        B = batch.t.shape[0]
        if B == 1:  # no vmap: a batched solver loop selects on its whole state every step
            first = jax.tree.map(lambda a: a[0], batch)
            ys, dys = jax.tree.map(lambda a: a[None], one(first, 0))
        else:
            ys, dys = jax.vmap(one)(batch, jnp.arange(B))
        m = batch.mask[..., None]
        return (batch.z - ys) * m, -dys * m[..., None]

    return residuals_and_jacobian


def _fit_batch(model: GreyBoxModel, theta0, batch: Experiment, prior: PriorBounds | None = None,
               *, diagonal, max_passes, max_steps, rtol, cost_rtol, n_local_batch=0,
               paired=False):
    """The whole estimator on one (padded) batch of experiments that share the parameters.

    Pure and jit/vmap-able: one `optimistix.least_squares` solve with [`RelaxedGaussNewton`][]
    (R relaxed by Eq. 11 at every Gauss-Newton step, the step halved on the likelihood of
    Eq. 10). Each step's residuals and their Jacobian come from one RK4 solve of the
    state with its forward sensitivities ([`simulate_sensitivities`][], equal to
    `jax.jacfwd` through the RK4 simulation), handed to optimistix as the derivative of the
    residual function ([`jacobian_once`][]; [`residuals_with_jacobian`][]). The uncertainty
    is computed from the Jacobian at the estimate that the last step already holds.
    `max_passes` is unused (kept for the signature: every step is a relaxation pass).
    `prior`: a prior and bounds ([`PriorBounds`][]): the prior's residuals join the cost,
    the step and the information matrix (`M = M_data + diag(1/std^2)`), the bounds make the
    step the bounded-variable one and the parameters held at an active bound leave the
    covariance (`covariance_held`). `paired`: the sensitivities' layout for a fit that runs
    under `vmap` with others ([`simulate_sensitivities`][]).
    """
    del max_passes
    noise = NoiseModel.of_data(batch.z, batch.mask, diagonal)

    residuals_and_jacobian = residuals_with_jacobian(model, batch, n_local_batch, paired)

    sol = solve_relaxed(residuals_and_jacobian, theta0, noise, rtol=rtol, cost_rtol=cost_rtol,
                        max_steps=max_steps, prior=prior)
    theta, v, R, cost = sol.theta, sol.v, sol.R, sol.cost  # v: (B, n, ny), the last accepted

    # Uncertainty at the estimate: Cramer-Rao, and corrected for coloured residuals.
    w, S = sol.whitened()
    Sw = -S  # d(whitened y)/d theta: (B, n, ny, p)
    M = fisher_information(Sw.reshape(-1, Sw.shape[-1]))
    # Lags never cross from one experiment into the next. Bartlett lag window spanning
    # LAG_WINDOW_FACTOR residual correlation lengths (>= 2 samples, <= a quarter record).
    def middle_of(S, v, mask):
        L = jnp.clip(LAG_WINDOW_FACTOR * correlation_length(v, mask), 2, jnp.sum(mask) / 4)
        return coloured_residual_middle(S, v, mask, L)

    middle = jax.vmap(middle_of)(Sw, w, batch.mask).sum(0)
    if prior is not None:  # the prior's residuals are white: the same in both
        M = M + prior.information()
        middle = middle + prior.information()
    cov_cr = covariance_held(M, held=sol.held)
    cov_c = covariance_held(M, middle, sol.held)
    finite = jnp.all(jnp.isfinite(w)) & jnp.all(jnp.isfinite(Sw))
    merged = merge_batch(model, theta, n_local_batch)
    first = flight_params(merged, 0)  # flight 0's locals
    return dict(theta=theta, R=R, cost=cost, finite=finite, params=first,
                std=jnp.sqrt(jnp.diag(cov_c)), std_cr=jnp.sqrt(jnp.diag(cov_cr)),
                corr=correlation(cov_c),
                passes=sol.accepted, steps=sol.steps, hist=sol.history,
                converged=sol.converged, M=M, cov_cr=cov_cr,
                cov=cov_c, lag1=jax.vmap(lag1_autocorrelation)(v, batch.mask),
                residual_corr=correlation(jnp.einsum("bki,bkj->ij", v, v)),
                colour=jax.vmap(colour_at_bandwidth)(v, batch.z, batch.mask),
                held=sol.held)


_fit_batch_jit = eqx.filter_jit(_fit_batch)


@eqx.filter_jit
def _fit_one_jit(model, theta0, exp: Experiment, prior=None, **kw):
    """[`_fit_batch`][] on a single experiment (the batch axis added inside the program)."""
    return _fit_batch(model, theta0, jax.tree.map(lambda a: a[None], exp), prior, **kw)


def fit_output_error(
    model: GreyBoxModel,
    exps: Sequence[Experiment],
    *,
    names: Sequence[str],
    start: str | GreyBoxModel = "least-squares",
    noise: str = "auto",
    max_passes: int = 12,
    max_steps: int = 60,
    rtol: float = 1e-10,
    cost_rtol: float = 1e-10,
    local_per_flight: bool | None = None,
    progress: bool = False,
    prior=None,
    bounds=None,
) -> FitResult:
    """[`fwid.fit`][] with `method="output-error"`, Eqs. (10)-(11): Gauss-Newton with R
    relaxed at every step, on experiments whose `x0` is set (`with_measured_x0`); with a
    `prior` and `bounds` (`fwid.estimate._prior`), the maximum a posteriori estimate within
    the bounds.

    **Arguments:** as [`fwid.fit`][].

    **Returns:** a [`fwid.FitResult`][].
    """
    check_noise(noise)
    names = list(names)
    t0 = time.perf_counter()
    per_flight = len(exps) > 1 and model.local and local_per_flight is not False
    n_local = len(exps) if per_flight else 0
    pb = None  # without a prior or bounds: the plain fit's program
    if prior is not None or bounds is not None:
        pb = prior_bounds(model, free_layout(model, n_local)[2], prior, bounds)
        pb = pb if has_any(pb) else None
    start_model, theta0 = prepare(model, exps, names, start, n_local)
    if pb is not None:
        theta0 = pb.clip(theta0)
    if progress:
        print(f"fwid: fitting {model.name} ({len(model.free)} parameters) to "
              f"{', '.join(names)} ...", flush=True)
    # padded (masked) to one of a few lengths: a flight of a new length reuses the program
    n = bucket_length(max(e.n for e in exps))
    fn, data = ((_fit_one_jit, pad_experiment(exps[0], n)) if len(exps) == 1
                else (_fit_batch_jit, stack_experiments(exps, n)))

    def run(diagonal: bool) -> FitResult:
        out = exported.call(fn, (start_model, theta0, data, pb), diagonal=diagonal,
                            max_passes=max_passes, max_steps=max_steps, rtol=rtol,
                            cost_rtol=cost_rtol, n_local_batch=n_local)
        return _result(model, start_model, theta0, out, names, n_local, max_steps,
                       "diagonal" if diagonal else "full", pb)

    if noise != "auto":
        result = run(noise == "diagonal")
    else:
        try:
            first = run(False)
        except FitDivergedError as e:  # a diagonal R may still rescue it
            first = e
        result = fall_back([first], lambda idx: [run(True)], [names], progress)[0]
    result = with_instability(result, exps, names)
    issue(result.warnings)
    if progress:
        state = "converged" if bool(result.converged) else "NOT converged"
        print(f"fwid: {model.name} fit {state} in {int(result.steps)} Gauss-Newton steps "
              f"({int(result.passes)} R relaxations), {time.perf_counter() - t0:.1f} s",
              flush=True)
    return result


def with_instability(result: FitResult, exps, names) -> FitResult:
    """`result` with the warning of an unstable identified model added, if there is one
    (`fwid.estimate._stability`)."""
    note = instability_warning(result.flight_model(0) if len(exps) > 1 else result.model,
                               exps, names)
    if note is None:
        return result
    return dataclasses.replace(result, warnings=(*result.warnings, note))


def _result(model, start_model, theta0, out, names, n_local, max_steps=None,
            noise="full", prior: PriorBounds | None = None) -> FitResult:
    """Check the estimator's raw output and wrap it in a [`fwid.FitResult`][]."""
    glob, loc, free_names = free_layout(model, n_local)
    if not (np.isfinite(float(out["cost"])) and bool(out["finite"])):
        raise FitDivergedError(
            f"{', '.join(names)}: the {model.name} fit diverged (the simulation blows up for "
            "every step tried from the start values; check the units and the trim); next: "
            f"{advise('diverged', 'output-error')}"
        )
    check_information(out, free_names, names)
    result = FitResult(
        model=eqx.tree_at(lambda m: m.params, start_model, dict(out["params"])),
        names=tuple(free_names),
        theta=out["theta"],
        std=out["std"],
        std_cr=out["std_cr"],
        cov=out["cov"],
        corr=out["corr"],
        R=out["R"],
        cost=out["cost"],
        cost_history=out["hist"],
        passes=out["passes"],
        steps=out["steps"],
        converged=out["converged"],
        start=theta0,
        noise=noise,
        lag1=jnp.max(jnp.reshape(out["lag1"], (-1, len(model.outputs))), axis=0),
        residual_corr=out["residual_corr"],
        colour=jnp.max(jnp.reshape(out["colour"], (-1, len(model.outputs))), axis=0),
        prior=prior,
        active=None if prior is None or not np.any(np.isfinite(np.asarray(prior.lower))
                                                   | np.isfinite(np.asarray(prior.upper)))
        else out["held"],
    )
    found = fit_warnings(result, names, max_steps, information=out["M"])
    return dataclasses.replace(result, warnings=tuple(found))
