"""The cycle-averaged pipeline (Section IV): flights -> cycle-averaged data -> output-error
fit (Eqs. 10-11) -> modes and validation."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .._errors import FitWarning, InputError
from ..data._flight import Flight
from ..estimate._each import fit_each
from ..estimate._fit import fit
from ..estimate._prior import prior_bounds
from ..estimate._problem import FitResult
from ..models._delfly import lateral, longitudinal
from ..models._greybox import GreyBoxModel
from ..simulation._averaged import averaged
from ..validate._modes import eigenvalues, modes
from ..validate._state_space import StateSpace, state_space
from ._closed_loop import ClosedLoop, closed_loop_test, closed_loop_warning
from ._flight_fit import FlightFit, evaluate

MODELS = {"lon": longitudinal, "lat": lateral}


@dataclass(frozen=True, repr=False)
class Identification:
    """What [`fwid.identify`][] found: the fit(s), their modes and their metrics.

    **Fields:**

    - `model`: the identified [`fwid.GreyBoxModel`][] (the mean of the per-flight estimates,
      or the joint estimate).
    - `flights`: the estimation flights' names.
    - `fits`: the [`fwid.FitResult`][] of each flight (one for a joint fit).
    - `estimation`, `validation`: a [`fwid.FlightFit`][] per estimation and held-out flight.
    - `joint`: whether one parameter set was fitted to all flights.
    - `consts`: the constants the modes are computed with (vehicle and trim).
    - `closed_loop`: the closed-loop test of each estimation flight's control
      ([`ClosedLoop`][], `None` where it could not run).
    - `warnings`: what the fits' own warnings do not say about the flights (a closed loop).
    - `pinned`: bias terms held at their start values because the flights carry no
      information on them (`{name: value}`; set by the diagnosis's fits, empty otherwise).

    `fit` is the first (or joint) fit, `eigenvalues` and `modes` those of `model`, and
    `state_space()` the linear system at the trim ([`fwid.StateSpace`][]).
    """

    model: GreyBoxModel
    flights: list[str]
    fits: list[FitResult]
    estimation: list[FlightFit]
    validation: list[FlightFit] = field(default_factory=list)
    joint: bool = False
    consts: dict[str, float] = field(default_factory=dict)
    closed_loop: list[ClosedLoop | None] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    pinned: dict[str, float] = field(default_factory=dict)

    @property
    def fit(self) -> FitResult:
        return self.fits[0]

    @property
    def eigenvalues(self) -> np.ndarray:
        return eigenvalues(self.model, self.consts)

    @property
    def modes(self) -> list[dict]:
        return modes(self.eigenvalues)

    def state_space(self, flight: int | None = None) -> StateSpace:
        """The identified model as `x' = A x + B u`, `y = C x + D u` at the trim, with named
        states, inputs and outputs ([`fwid.StateSpace`][]: `.to_scipy()`, `.to_control()`).
        `flight`: the model of that estimation flight's own fit (default: the summary model,
        the mean of the per-flight estimates or the joint fit)."""
        model = self.model if flight is None else (
            self.fits[flight].model if len(self.fits) > 1 else self.model)
        return state_space(model, self.consts)

    def __repr__(self) -> str:
        conv = sum(bool(f.converged) for f in self.fits)
        osc = [m for m in self.modes if m["kind"] == "oscillatory"]
        mode = (f", oscillatory mode wn={osc[0]['wn']:.3g} rad/s zeta={osc[0]['zeta']:.3g}"
                if osc else "")
        return (f"Identification(model={self.model.name!r}, flights={self.flights}, "
                f"{'joint' if self.joint else 'per-flight'} fit(s): {conv}/{len(self.fits)} "
                f"converged, {len(self.model.free)} free parameters{mode}, "
                f"validation flights={[v.name for v in self.validation]})")


def get_model(model: str | GreyBoxModel) -> GreyBoxModel:
    if isinstance(model, GreyBoxModel):
        return model
    try:
        return MODELS[model]()
    except KeyError:
        raise InputError(
            f"unknown model {model!r}: choose one of {', '.join(MODELS)} or pass a GreyBoxModel"
        ) from None


def _mean_model(model: GreyBoxModel, fits: Sequence[FitResult]) -> GreyBoxModel:
    values = {k: float(np.mean([float(f.model.params[k]) for f in fits])) for k in model.free}
    return model.with_params(values)


def _say_missing_forces(model: GreyBoxModel, flights: Sequence[Flight]) -> None:
    """A model with a force model fitted to flights without the force columns: the fit still
    runs on the states, but starts differently and reports no force metrics. Say so."""
    if not model.force_names:
        return
    lacking = [f.name for f in flights if not all(c in f for c in model.force_names)]
    if lacking:
        warnings.warn(
            f"{', '.join(lacking)}: no force/moment columns {' '.join(model.force_names)}; the "
            f"{model.name} model is fitted to the states alone, from the state-derivative "
            "regression start instead of the reconstructed forces (Sec. IV.B), and no force "
            "metrics are reported. Add the columns (the guide's 'Formats and interfaces' page, "
            "docs/reference/formats.md) to use them.",
            UserWarning, stacklevel=3)


def identify(
    flights: Sequence[Flight],
    model: str | GreyBoxModel = "lon",
    *,
    validate: Sequence[Flight] = (),
    joint: bool = False,
    cutoff: float = 5.0,
    noise_cutoff: float = 40.0,
    start: str | GreyBoxModel = "least-squares",
    progress: bool = False,
    prior=None,
    bounds=None,
    method: str = "output-error",
    noise: str = "auto",
) -> Identification:
    """Identify the cycle-averaged model from flights, as in the paper's Section IV.

    Each flight is split (Sec. III.B) and its cycle-averaged part, inputs included, is fitted
    by output-error ML (Eqs. 10-11) from a least-squares start. Without `joint`, each flight
    gets its own fit (the paper's practice) and the summary model is the mean of their
    estimates; with `joint`, one parameter set is fitted to all flights together, each with
    its own initial state, trim and bias terms. Validation flights are simulated with the
    summary model, their bias terms re-estimated.

    **Arguments:**

    - `flights`: the estimation flights ([`fwid.load_flights`][]).
    - `model`: `"lon"`, `"lat"` or a [`fwid.GreyBoxModel`][].
    - `validate`: held-out flights to score the model on.
    - `joint`: one parameter set for all flights (default: one fit per flight).
    - `cutoff`: the split between the cycle-averaged and the flapping part [Hz] (default 5).
    - `noise_cutoff`: the noise low-pass applied first [Hz] (default 40).
    - `start`: passed to [`fwid.fit`][]: `"least-squares"`, `"model"` (the model's values)
      or a model whose values to start from.
    - `progress`: print a line per stage.
    - `prior`, `bounds`: a Gaussian prior on parameters and bounds, passed to
      [`fwid.fit`][] (with per-flight fits, every flight's fit gets them).
    - `method`: the estimator, passed to [`fwid.fit`][]: `"output-error"` (the paper's),
      `"multiple-shooting"` (an unstable vehicle), `"filter-error"` (process noise,
      closed-loop flights) or `"equation-error"` (least squares of the reconstructed loads:
      no simulation, where an unstable vehicle flown in closed loop is begun; its loads
      metrics are those predicted at the measured states).
    - `noise`: the measurement-noise covariance R, passed to [`fwid.fit`][]: `"auto"` (a
      full R, or a diagonal one where the full one fails or the residuals carry model
      error), `"full"` or `"diagonal"`.

    **Returns:** an [`fwid.Identification`][].
    """
    model = get_model(model)
    flights = list(flights)
    if not flights:
        raise InputError("no flights to identify from")
    if prior is not None or bounds is not None:  # bad names or values: say so now
        prior_bounds(model, list(model.free), prior, bounds)
    _say_missing_forces(model, list(flights) + list(validate))
    loops = [closed_loop_test(f, model.inputs[0], model.states, cutoff)
             for f in flights] if model.inputs else []
    # the warning is output error's: the other methods follow the measured states
    notes = [w for w in [closed_loop_warning(loops, model.name)]
             if w is not None and method == "output-error"]
    for w in notes:
        warnings.warn(w, FitWarning, stacklevel=2)
    exps = [averaged(f, model, cutoff, noise_cutoff) for f in flights]
    names = [f.name for f in flights]
    if joint or len(exps) == 1:
        fits = [fit(model, exps, names=names, start=start, progress=progress, prior=prior,
                    bounds=bounds, method=method, noise=noise)]
        summary = fits[0].model
        estimation = []
        for i, (e, n) in enumerate(zip(exps, names)):
            estimation.append(evaluate(fits[0].flight_model(i), e, n, refit_local=False,
                                       method=method))
    else:
        fits = fit_each(model, exps, names=names, start=start, progress=progress, prior=prior,
                        bounds=bounds, method=method, noise=noise)
        summary = _mean_model(model, fits)
        estimation = [evaluate(f.model, e, n, refit_local=False, method=method)
                      for f, e, n in zip(fits, exps, names)]
    validation = [
        evaluate(summary, averaged(f, model, cutoff, noise_cutoff), f.name, method=method)
        for f in validate
    ]
    consts = {k: float(v) for k, v in exps[0].consts.items()}
    return Identification(model=summary, flights=names, fits=fits, estimation=estimation,
                          validation=validation, joint=joint, consts=consts,
                          closed_loop=loops, warnings=notes)
