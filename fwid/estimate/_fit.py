"""[`fwid.fit`][]: one entry to every estimation method, dispatched by `method=`."""

from __future__ import annotations

from collections.abc import Sequence

from .._errors import InputError
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment, with_measured_x0
from ._equation_error import fit_equation_error
from ._filter_error import fit_filter_error
from ._noise import check_noise
from ._output_error import fit_output_error
from ._problem import FitResult
from ._shooting import fit_shooting

#: The estimation methods [`fwid.fit`][] and [`fwid.fit_each`][] take with `method=`.
METHODS = ("output-error", "multiple-shooting", "filter-error", "equation-error")


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
    prior=None,
    bounds=None,
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
    - `max_steps`: the most Gauss-Newton steps (each relaxes R); this alone bounds the fit.
    - `max_passes`: deprecated and ignored: R is relaxed at every Gauss-Newton step, so there
      are no separate relaxation passes to count. Passing it changes nothing; it will be
      removed in a future version (bound the fit with `max_steps`).
    - `rtol`: stop when the next step is below `1e-9 + rtol |theta_i|` for every parameter,
      in units in which each has unit sensitivity (about its standard deviation), ...
    - `cost_rtol`: ... and the cost has settled to `cost_rtol (1 + |cost|)`.
    - `local_per_flight`: with several experiments, estimate the model's `local` parameters
      (bias terms) separately for each one (named `name@i`); otherwise they are shared.
      Default (`None`): per flight for output error, shared for multiple shooting and filter
      error (`True` makes filter error estimate them per flight too).
    - `progress`: print a line when the fit starts and ends.
    - `method`: `"output-error"` (the above); `"multiple-shooting"` for unstable vehicles
      ([`fwid.fit_shooting`][]; option `segments` per experiment, default segments of 10
      samples and at least 0.5 s); `"filter-error"` for data with process noise
      ([`fwid.fit_filter_error`][]); `"equation-error"`: least squares of the reconstructed
      loads on the states and inputs, no simulation (`fwid.estimate._equation_error`: the
      start of the others, and where an unstable vehicle flown in closed loop is begun).
    - `prior`: a Gaussian prior on parameters, `{name: (mean, std)}` (or
      `{name: {"mean": .., "std": ..}}`, a [`fwid.FitResult`][], an identification, a
      `report.json` dict or file: see [`fwid.prior_from`][], which also scales it). Each
      adds the residual `(theta - mean) / std` to the cost (the maximum a posteriori
      estimate; Jategaonkar's "a priori information"), to the Gauss-Newton step and to the
      information matrix, `M = M_data + diag(1/std^2)`, behind `std` and `std_cr`. A name
      of a per-flight parameter (`bq`) sets every flight's copy (`bq@0`, ...).
    - `bounds`: `{name: (low, high)}` (`None` an open side; or `{name: {"low", "high"}}`):
      the estimate stays within them, by the bounded-variable Gauss-Newton step
      (Jategaonkar 2015, Sec. 4.13.3: the start clipped into the bounds; a parameter at a
      bound whose step points out is held there for that step, the step recomputed for
      the others and projected into the bounds). `FitResult.active` says which bounds are
      active at the estimate; such a parameter's std is NaN, the others' conditional on it
      (see [`fwid.FitResult`][]). Output error only.
    - `options`: the chosen method's own options.

    **Returns:** a [`fwid.FitResult`][].

    **Raises:** [`fwid.InputError`][] when an experiment's time axis is not uniform or its
    `u`, `z`, `x0` do not match the model's inputs, outputs and states (or `x0` is missing
    where the outputs are not the states and do not include them all; where they include
    them, a missing `x0` is their first measured sample, or a prior or bounds name a
    parameter that is not free, give a std <= 0 or low >= high, or come with a method other
    than output error), [`fwid.ExcitationError`][] when the data cannot
    identify a parameter, [`fwid.FitDivergedError`][] when the cost cannot be made finite.
    """
    check_noise(noise)
    exps = [experiments] if isinstance(experiments, Experiment) else list(experiments)
    exps = [with_measured_x0(model, e) for e in exps]
    names = list(names) if names is not None else [f"exp{i}" for i in range(len(exps))]
    common = dict(names=names, start=start, noise=noise, max_steps=max_steps, rtol=rtol,
                  cost_rtol=cost_rtol, progress=progress)
    if method == "output-error":
        if options:
            raise TypeError(f"fwid.fit: unexpected option(s) {', '.join(sorted(options))} for "
                            "method='output-error'")
        return fit_output_error(model, exps, max_passes=max_passes,
                                local_per_flight=local_per_flight, prior=prior,
                                bounds=bounds, **common)
    if method in METHODS and (prior is not None or bounds is not None):
        raise InputError(f"fwid.fit: prior= and bounds= work with method='output-error' only, "
                         f"not method={method!r}; drop them or fit by output error")
    if method == "multiple-shooting":
        return fit_shooting(model, exps, **common, **options)
    if method == "equation-error":
        return fit_equation_error(model, exps, local_per_flight=local_per_flight, **common,
                                  **options)
    if method == "filter-error":
        if local_per_flight is not None:
            options = {**options, "local_per_flight": local_per_flight}
        return fit_filter_error(model, exps, **common, **options)
    raise ValueError(f"method must be one of {', '.join(map(repr, METHODS))}, not {method!r}")
