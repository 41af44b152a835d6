"""Output-error maximum likelihood estimation, Eqs. (10)-(11), minimised by Gauss-Newton."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .._errors import ExcitationError, FitDivergedError
from ..models._greybox import GreyBoxModel
from ..simulation._buckets import bucket_length, pad_experiment
from ..simulation._checks import check_experiment
from ..simulation._experiment import Experiment, stack_experiments, with_measured_x0
from ..simulation._simulate import simulate, simulate_sensitivities
from . import _exported as exported
from ._colour import colour_at_bandwidth
from ._gauss_newton import NoiseModel, solve_relaxed
from ._noise import check_noise, fall_back
from ._stability import instability_warning
from ._start import least_squares_start
from ._uncertainty import (
    coloured_residual_middle,
    correlation,
    correlation_length,
    covariance,
    lag1_autocorrelation,
    fisher_information,
)
from ._warnings import fit_warnings, issue

# The Bartlett lag window of the coloured-residual bounds spans this many residual
# correlation lengths (see `benchmarks/calibration.py` for how it was chosen).
LAG_WINDOW_FACTOR = 4


class FitResult(eqx.Module):
    """The output of [`fwid.fit`][]: estimates, their uncertainty and the fit's history.

    **Fields:**
    - `model`: the model with its parameters set to the estimates.
    - `names`: the free parameters, in the order of `theta`, `std`, `cov`; in a joint fit of
      several flights the model's `local` parameters (bias terms) are estimated per flight
      and named `bq@0`, `bq@1`, ... after the flight's index.
    - `theta`: the estimates of the free parameters.
    - `std`: standard deviations corrected for coloured residuals (Morelli and Klein, with a
      Bartlett lag window twice the residuals' correlation length).
    - `std_cr`: the plain Cramer-Rao standard deviations, `sqrt(diag(M^-1))`.
    - `cov`: the covariance matrix behind `std`; `corr` its correlation matrix.
    - `R`: the measurement-noise covariance estimate, Eq. (11).
    - `cost`: the negative log-likelihood, Eq. (10), at the estimate.
    - `cost_history`: the cost after each accepted Gauss-Newton step, each of which also
      relaxes R (NaN after the last).
    - `passes`, `steps`: R relaxations (accepted Gauss-Newton steps) and Gauss-Newton
      steps taken (evaluations, the start and any halved steps included).
    - `converged`: whether the cost and the parameters settled within tolerance.
    - `start`: the least-squares start values of the free parameters.
    - `warnings`: what should not be trusted about this fit (not converged, R
      ill-conditioned, residuals of model error or process noise, an unstable model growing
      beyond 100-fold over the record, parameters correlated beyond 0.98, not finite), one
      sentence each;
      [`fwid.fit`][] also issues each as a [`fwid.FitWarning`][].
    - `noise`: the R the estimates belong to, `"full"` or `"diagonal"` (with `noise="auto"`
      a diagonal R replaces a full one that failed, see `fwid.estimate._noise`).
    - `lag1`: each output's residual autocorrelation at one sample (the largest over the
      experiments): near 0 for white measurement noise, near 1 for coloured residuals
      (process noise or a missing effect).
    - `colour`: each output's residual autocorrelation at the lag that spans half a period
      at the data's bandwidth (`fwid.estimate._colour`; the largest over the experiments):
      near 0 for measurement noise, white or pre-filtered, near 1 for model error. This,
      not `lag1`, is what the model-error warning and `noise="auto"` read.
    - `residual_corr`: the correlation matrix of the residuals between the outputs (whatever
      R the fit used).
    """

    model: GreyBoxModel
    names: tuple[str, ...] = eqx.field(static=True)
    theta: Float[Array, " p"]
    std: Float[Array, " p"]
    std_cr: Float[Array, " p"]
    cov: Float[Array, "p p"]
    corr: Float[Array, "p p"]
    R: Float[Array, "ny ny"]
    cost: Float[Array, ""]
    cost_history: Float[Array, " passes"]
    passes: Int[Array, ""]
    steps: Int[Array, ""]
    converged: Bool[Array, ""]
    start: Float[Array, " p"]
    warnings: tuple[str, ...] = eqx.field(static=True, default=())
    noise: str = eqx.field(static=True, default="full")
    lag1: Float[Array, " ny"] | None = None
    residual_corr: Float[Array, "ny ny"] | None = None
    colour: Float[Array, " ny"] | None = None

    @property
    def params(self) -> dict:
        return self.model.params

    def flight_model(self, i: int) -> GreyBoxModel:
        """The model with flight `i`'s own local parameters (bias terms) of a joint fit."""
        local = {k: self.theta[self.names.index(f"{k}@{i}")]
                 for k in self.model.local if f"{k}@{i}" in self.names}
        return self.model.with_params(local)

    def table(self) -> dict[str, dict[str, float]]:
        """`{name: {value, std, std_cr, rel_std_pct}}`, Table 1's layout."""
        out = {}
        for i, k in enumerate(self.names):
            v, s = float(self.theta[i]), float(self.std[i])
            out[k] = dict(value=v, std=s, std_cr=float(self.std_cr[i]),
                          rel_std_pct=100.0 * abs(s / v) if v != 0 else float("inf"))
        return out


def _simulate_batch(model, params, batch: Experiment):
    """Simulate every experiment of a batch; `params` values are scalars or `(B,)` arrays."""
    B = batch.t.shape[0]
    pb = {k: jnp.broadcast_to(v, (B,)) for k, v in params.items()}
    return jax.vmap(lambda e, p: simulate(model, e, p)[1])(batch, pb)


def _raw_residuals(model, params, batch):
    y = _simulate_batch(model, params, batch)
    return (batch.z - y) * batch.mask[..., None]


def _free_layout(model: GreyBoxModel, n_local_batch: int):
    """The layout of the free vector: global names, local names, and every entry's name."""
    glob = [k for k in model.free if k not in model.local or n_local_batch == 0]
    loc = [k for k in model.free if k in model.local and n_local_batch > 0]
    names = glob + [f"{k}@{b}" for k in loc for b in range(n_local_batch)]
    return glob, loc, names


def _merge_batch(model: GreyBoxModel, theta, n_local_batch: int):
    """Parameter dict from the vector `[global free..., local free x B]` (locals per flight)."""
    glob, loc, _ = _free_layout(model, n_local_batch)
    params = dict(model.params)
    for i, k in enumerate(glob):
        params[k] = theta[i]
    for j, k in enumerate(loc):
        start = len(glob) + j * n_local_batch
        params[k] = theta[start:start + n_local_batch]
    return params


def flight_params(merged: dict, b) -> dict:
    """Flight `b`'s parameters from [`_merge_batch`][]'s dict (a local parameter is an array
    with one value per flight, a global one a scalar)."""
    return {k: (v if jnp.ndim(v) == 0 else v[b]) for k, v in merged.items()}


def _fit_batch(model: GreyBoxModel, theta0, batch: Experiment, *, diagonal, max_passes,
               max_steps, rtol, cost_rtol, n_local_batch=0):
    """The whole estimator on one (padded) batch of experiments that share the parameters.

    Pure and jit/vmap-able: one `optimistix.least_squares` solve with [`RelaxedGaussNewton`][]
    (R relaxed by Eq. 11 at every Gauss-Newton step, the step halved on the likelihood of
    Eq. 10). Each step's residuals and their Jacobian come from one RK4 solve of the
    state with its forward sensitivities ([`simulate_sensitivities`][], equal to
    `jax.jacfwd` through the RK4 simulation), handed to optimistix as the derivative of the
    residual function ([`jacobian_once`][]). The uncertainty is computed from the Jacobian
    at the estimate that the last step already holds. `max_passes` is unused (kept for the
    signature: every step is a relaxation pass).
    """
    del max_passes
    noise = NoiseModel.of_data(batch.z, batch.mask, diagonal)

    def residuals_and_jacobian(theta):
        def one(e, b):
            def params_of(th):  # flight b's parameters (its own local ones in joint fits)
                return flight_params(_merge_batch(model, th, n_local_batch), b)
            return simulate_sensitivities(model, e, params_of, theta)

        B = batch.t.shape[0]
        if B == 1:  # no vmap: a batched solver loop selects on its whole state every step
            first = jax.tree.map(lambda a: a[0], batch)
            ys, dys = jax.tree.map(lambda a: a[None], one(first, 0))
        else:
            ys, dys = jax.vmap(one)(batch, jnp.arange(B))
        m = batch.mask[..., None]
        return (batch.z - ys) * m, -dys * m[..., None]

    sol = solve_relaxed(residuals_and_jacobian, theta0, noise, rtol=rtol, cost_rtol=cost_rtol,
                        max_steps=max_steps)
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
    cov_cr = covariance(M)
    cov_c = covariance(M, middle)
    finite = jnp.all(jnp.isfinite(w)) & jnp.all(jnp.isfinite(Sw))
    merged = _merge_batch(model, theta, n_local_batch)
    first = flight_params(merged, 0)  # flight 0's locals
    return dict(theta=theta, R=R, cost=cost, finite=finite, params=first,
                std=jnp.sqrt(jnp.diag(cov_c)), std_cr=jnp.sqrt(jnp.diag(cov_cr)),
                corr=correlation(cov_c),
                passes=sol.accepted, steps=sol.steps, hist=sol.history,
                converged=sol.converged, M=M, cov_cr=cov_cr,
                cov=cov_c, lag1=jax.vmap(lag1_autocorrelation)(v, batch.mask),
                residual_corr=correlation(jnp.einsum("bki,bkj->ij", v, v)),
                colour=jax.vmap(colour_at_bandwidth)(v, batch.z, batch.mask))


_fit_batch_jit = eqx.filter_jit(_fit_batch)


@eqx.filter_jit
def _fit_one_jit(model, theta0, exp: Experiment, **kw):
    """[`_fit_batch`][] on a single experiment (the batch axis added inside the program)."""
    return _fit_batch(model, theta0, jax.tree.map(lambda a: a[None], exp), **kw)


def _check_excitation(model: GreyBoxModel, exps: Sequence[Experiment], names: Sequence[str]):
    for e, name in zip(exps, names):
        u = np.asarray(e.u)
        still = [model.inputs[j] for j in range(u.shape[1]) if np.ptp(u[:, j]) < 1e-12]
        if len(still) == u.shape[1] and u.shape[1] > 0:
            raise ExcitationError(
                f"{name}: input {', '.join(repr(s) for s in still)} never moves: there is no "
                "manoeuvre to identify the model from; use a flight with a doublet/3211 input"
            )


def _check_information(result, names, flights):
    M = np.asarray(result["M"])
    d = np.sqrt(np.clip(np.diag(M), 0, None))
    bad = [names[i] for i in range(len(names)) if not np.isfinite(d[i]) or d[i] <= 1e-10 * d.max()]
    if bad:
        raise ExcitationError(
            f"{', '.join(flights)}: the data carry no information on parameter"
            f"{'s' if len(bad) > 1 else ''} {', '.join(bad)} (too little excitation); fix "
            "them (`model.with_free(...)`) or add flights whose inputs excite them"
        )


def fit(
    model: GreyBoxModel,
    experiments: Experiment | Sequence[Experiment],
    *,
    names: Sequence[str] | None = None,
    start: str | GreyBoxModel = "least-squares",
    noise: str = "auto",
    max_passes: int = 12,
    max_steps: int = 60,
    rtol: float = 1e-10,
    cost_rtol: float = 1e-10,
    local_per_flight: bool | None = None,
    progress: bool = False,
    method: str = "output-error",
    **options,
) -> FitResult:
    """Estimate the free parameters of `model` by output-error maximum likelihood.

    The cost is the negative log-likelihood of Eq. (10), minimised by Gauss-Newton
    (optimistix) with the measurement-noise covariance R relaxed (Eq. 11) at every step, as
    in Jategaonkar's output-error method: R from the current residuals, the Gauss-Newton step
    `(sum J^T R^-1 J) dtheta = -sum J^T R^-1 v`, halved until the likelihood decreases. The
    Jacobians come from the forward sensitivity equations integrated with the state in one
    diffrax RK4 solve. Several experiments are fitted together (one parameter set, each
    integrated from its own initial state).

    **Arguments:**
    - `model`: the [`fwid.GreyBoxModel`][]; its free parameters are estimated.
    - `experiments`: one [`fwid.Experiment`][] or a list of them.
    - `names`: the experiments' names, for messages (default `exp0`, `exp1`, ...).
    - `start`: `"least-squares"` (equation error, as the paper), `"model"` (the model's
      current values), or a model whose values to start from.
    - `noise`: `"full"` R (Eq. 11), `"diagonal"` (uncorrelated output noise), or `"auto"`:
      a full R, replaced by a diagonal one when the full-R fit does not converge, is not
      finite or ends with an ill-conditioned R (`FitResult.noise` says which was used).
    - `max_steps`: Gauss-Newton steps (each relaxes R). `max_passes` is accepted for
      compatibility and unused (R used to be relaxed between whole Gauss-Newton solves).
    - `rtol`: stop when the next step is below `1e-9 + rtol |theta_i|` for every parameter,
      in units in which each has unit sensitivity (about its standard deviation), ...
    - `cost_rtol`: ... and the cost has settled to `cost_rtol (1 + |cost|)`.
    - `local_per_flight`: with several experiments, estimate the model's `local` parameters
      (bias terms) separately for each one (named `name@i`); otherwise they are shared.
      Default (`None`): per flight for output error, shared for multiple shooting and filter
      error (`True` makes filter error estimate them per flight too).
    - `progress`: print a line when the fit starts and ends.
    - `method`: `"output-error"` (the above); `"multiple-shooting"` for unstable vehicles
      (`fwid.estimate._shooting`; option `segments` per experiment, default 10 samples each);
      `"filter-error"` for data with process noise (`fwid.estimate._filter_error`).
    - `options`: the chosen method's own options.

    **Returns:** a [`fwid.FitResult`][].

    **Raises:** [`fwid.InputError`][] when an experiment's time axis is not uniform or its
    `u`, `z`, `x0` do not match the model's inputs, outputs and states (or `x0` is missing
    where the outputs are not the states and do not include them all; where they include
    them, a missing `x0` is their first measured sample), [`fwid.ExcitationError`][] when the data cannot
    identify a parameter, [`fwid.FitDivergedError`][] when the cost cannot be made finite.
    """
    check_noise(noise)
    exps = [experiments] if isinstance(experiments, Experiment) else list(experiments)
    exps = [with_measured_x0(model, e) for e in exps]
    names = list(names) if names is not None else [f"exp{i}" for i in range(len(exps))]
    if method != "output-error" or options:
        from ._methods import fit_method
        if method == "filter-error" and local_per_flight is not None:
            options = {**options, "local_per_flight": local_per_flight}
        return fit_method(method, model, exps, options, names=names, start=start, noise=noise,
                          max_steps=max_steps, rtol=rtol, cost_rtol=cost_rtol,
                          progress=progress, **options)
    t0 = time.perf_counter()
    per_flight = len(exps) > 1 and model.local and local_per_flight is not False
    n_local = len(exps) if per_flight else 0
    start_model, theta0 = _prepare(model, exps, names, start, n_local)
    if progress:
        print(f"fwid: fitting {model.name} ({len(model.free)} parameters) to "
              f"{', '.join(names)} ...", flush=True)
    # padded (masked) to one of a few lengths: a flight of a new length reuses the program
    n = bucket_length(max(e.n for e in exps))
    fn, data = ((_fit_one_jit, pad_experiment(exps[0], n)) if len(exps) == 1
                else (_fit_batch_jit, stack_experiments(exps, n)))

    def run(diagonal: bool) -> FitResult:
        out = exported.call(fn, (start_model, theta0, data), diagonal=diagonal,
                            max_passes=max_passes, max_steps=max_steps, rtol=rtol,
                            cost_rtol=cost_rtol, n_local_batch=n_local)
        return _result(model, start_model, theta0, out, names, n_local, max_steps,
                       "diagonal" if diagonal else "full")

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


def _prepare(model, exps, names, start, n_local):
    """Checks and start values: the start model and the initial free vector."""
    if not model.free:
        raise ValueError(f"model {model.name!r} has no free parameters to estimate")
    for e, name in zip(exps, names):
        if e.t.dtype != jnp.float64:
            raise TypeError("fwid.fit needs float64 arrays: enable jax_enable_x64 (import fwid)")
        check_experiment(model, e, name)
    _check_excitation(model, exps, names)
    if isinstance(start, GreyBoxModel):
        start_model = model.with_params(start.params)
    elif start == "least-squares":
        start_model = least_squares_start(model, exps)
    elif start == "model":
        start_model = model
    else:
        raise ValueError(f"start must be 'least-squares', 'model' or a model, not {start!r}")
    glob, loc, _ = _free_layout(model, n_local)
    vals = jax.device_get({k: start_model.params[k] for k in (*glob, *loc)})
    theta0 = jnp.asarray(np.concatenate([
        np.array([vals[k] for k in glob], dtype=float),
        *[np.full(n_local, vals[k], dtype=float) for k in loc],
    ]))
    return start_model, theta0


def _result(model, start_model, theta0, out, names, n_local, max_steps=None,
            noise="full") -> FitResult:
    """Check the estimator's raw output and wrap it in a [`fwid.FitResult`][]."""
    glob, loc, free_names = _free_layout(model, n_local)
    if not (np.isfinite(float(out["cost"])) and bool(out["finite"])):
        raise FitDivergedError(
            f"{', '.join(names)}: the {model.name} fit diverged (the simulation blows up for "
            "every step tried from the start values); check the units and the trim, or give "
            "start values (`start=model.with_params(...)`)"
        )
    _check_information(out, free_names, names)
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
    )
    found = fit_warnings(result, names, max_steps, information=out["M"])
    return dataclasses.replace(result, warnings=tuple(found))
