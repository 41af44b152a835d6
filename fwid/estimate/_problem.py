"""The estimation problem every method solves: the free-parameter layout, the prepared
experiments and start values, and [`fwid.FitResult`][].

The methods (output error `_output_error.py`, multiple shooting `_shooting.py`, filter error
`_filter_error.py`) stand beside each other on top of this module; [`fwid.fit`][]
(`_fit.py`) dispatches to them.
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .._errors import ExcitationError
from ..models._greybox import GreyBoxModel
from ..simulation._checks import check_experiment
from ..simulation._experiment import Experiment
from .._advice import advise
from ._prior import PriorBounds
from ._start import least_squares_start


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
    - `prior`: the prior and the bounds the fit used (`fwid.estimate.PriorBounds` over `names`: means,
      `1/std`, lower and upper bounds), `None` for a fit without either. With a prior,
      `cost` and `cost_history` include its part `1/2 sum ((theta - mean) / std)^2` (the
      negative log-posterior) and the information behind `std`, `std_cr` and `cov` its
      `diag(1/std^2)`.
    - `active`: per parameter, -1 / +1 where the estimate sits at an active lower / upper
      bound (the data pull it beyond), else 0 (`None` without bounds). Such a parameter's
      `std`, `std_cr` and its row and column of `cov` and `corr` are NaN (its spread is
      one-sided, not Gaussian), and those of the others are conditional on it held at the
      bound; see `active_bounds`.
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
    prior: PriorBounds | None = None
    active: Int[Array, " p"] | None = None

    @property
    def params(self) -> dict:
        return self.model.params

    @property
    def active_bounds(self) -> dict[str, str]:
        """`{name: "low" | "high"}`: the parameters at an active bound."""
        if self.active is None:
            return {}
        side = {-1: "low", 1: "high"}
        return {k: side[int(a)] for k, a in zip(self.names, np.asarray(self.active)) if a}

    def prior_table(self) -> dict[str, dict[str, float]]:
        """`{name: {"mean", "std"}}`: the prior the fit used (empty without one)."""
        if self.prior is None:
            return {}
        mean, w = np.asarray(self.prior.mean), np.asarray(self.prior.weight)
        return {k: {"mean": float(mean[i]), "std": float(1.0 / w[i])}
                for i, k in enumerate(self.names) if w[i] > 0}

    def bounds_table(self) -> dict[str, dict]:
        """`{name: {"low", "high", "active", "at"}}`: the bounds the fit used (`None` an open
        side), whether one is active at the estimate and which (`"low"`, `"high"`, `None`)."""
        if self.prior is None:
            return {}
        lo, hi = np.asarray(self.prior.lower), np.asarray(self.prior.upper)
        active = self.active_bounds
        return {k: {"low": float(lo[i]) if np.isfinite(lo[i]) else None,
                    "high": float(hi[i]) if np.isfinite(hi[i]) else None,
                    "active": k in active, "at": active.get(k)}
                for i, k in enumerate(self.names) if np.isfinite(lo[i]) or np.isfinite(hi[i])}

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


def free_layout(model: GreyBoxModel, n_local_batch: int):
    """The layout of the free vector: global names, local names, and every entry's name."""
    glob = [k for k in model.free if k not in model.local or n_local_batch == 0]
    loc = [k for k in model.free if k in model.local and n_local_batch > 0]
    names = glob + [f"{k}@{b}" for k in loc for b in range(n_local_batch)]
    return glob, loc, names


def merge_batch(model: GreyBoxModel, theta, n_local_batch: int):
    """Parameter dict from the vector `[global free..., local free x B]` (locals per flight)."""
    glob, loc, _ = free_layout(model, n_local_batch)
    params = dict(model.params)
    for i, k in enumerate(glob):
        params[k] = theta[i]
    for j, k in enumerate(loc):
        start = len(glob) + j * n_local_batch
        params[k] = theta[start:start + n_local_batch]
    return params


def flight_columns(model: GreyBoxModel, n_local_batch: int, b):
    """The entries of the free vector (`free_layout`) that flight `b`'s simulation depends
    on: every global parameter, then its own value of each local one (`b` may be traced)."""
    glob, loc, _ = free_layout(model, n_local_batch)
    return jnp.concatenate([jnp.arange(len(glob)),
                            len(glob) + jnp.arange(len(loc)) * n_local_batch + b])


def flight_params(merged: dict, b) -> dict:
    """Flight `b`'s parameters from [`merge_batch`][]'s dict (a local parameter is an array
    with one value per flight, a global one a scalar)."""
    return {k: (v if jnp.ndim(v) == 0 else v[b]) for k, v in merged.items()}


def check_excitation(model: GreyBoxModel, exps: Sequence[Experiment], names: Sequence[str]):
    for e, name in zip(exps, names):
        u = np.asarray(e.u)
        still = [model.inputs[j] for j in range(u.shape[1]) if np.ptp(u[:, j]) < 1e-12]
        if len(still) == u.shape[1] and u.shape[1] > 0:
            raise ExcitationError(
                f"{name}: input {', '.join(repr(s) for s in still)} never moves: there is no "
                "manoeuvre to identify the model from; use a flight with a doublet/3211 input"
            )


def check_information(result, names, flights, method: str = "output-error"):
    M = np.asarray(result["M"])
    d = np.sqrt(np.clip(np.diag(M), 0, None))
    bad = [names[i] for i in range(len(names)) if not np.isfinite(d[i]) or d[i] <= 1e-10 * d.max()]
    if bad:
        raise ExcitationError(
            f"{', '.join(flights)}: the data carry no information on parameter"
            f"{'s' if len(bad) > 1 else ''} {', '.join(bad)} (too little excitation); next: "
            f"{advise('no-information', method, bad[0])}",
            parameters=bad,
        )


def prepare(model, exps, names, start, n_local):
    """Checks and start values: the start model and the initial free vector."""
    if not model.free:
        raise ValueError(f"model {model.name!r} has no free parameters to estimate")
    for e, name in zip(exps, names):
        if e.t.dtype != jnp.float64:
            raise TypeError("fwid.fit needs float64 arrays: enable jax_enable_x64 (import fwid)")
        check_experiment(model, e, name)
    check_excitation(model, exps, names)
    if isinstance(start, GreyBoxModel):
        start_model = model.with_params(start.params)
    elif start == "least-squares":
        start_model = least_squares_start(model, exps)
    elif start == "model":
        start_model = model
    else:
        raise ValueError(f"start must be 'least-squares', 'model' or a model, not {start!r}")
    glob, loc, _ = free_layout(model, n_local)
    vals = jax.device_get({k: start_model.params[k] for k in (*glob, *loc)})
    theta0 = jnp.asarray(np.concatenate([
        np.array([vals[k] for k in glob], dtype=float),
        *[np.full(n_local, vals[k], dtype=float) for k in loc],
    ]))
    return start_model, theta0
