"""The identification pipeline: flights -> cycle-averaged data -> fit -> validation.

This glues the stages together for the command line and for users who want the paper's
workflow in one call; every stage is also usable on its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ._errors import InputError
from .data._flight import Flight
from .decompose import cycle_averaged
from .estimate._local import refit_local_affine
from .estimate._output_error import FitResult, fit, fit_each
from .models._delfly import lateral, longitudinal
from .models._greybox import GreyBoxModel
from .simulate._experiment import Experiment, experiment
from .simulate._simulate import simulate, simulate_forces
from .validate._metrics import fit_metrics
from .validate._modes import eigenvalues, modes

MODELS = {"lon": longitudinal, "lat": lateral}


@dataclass(frozen=True)
class FlightFit:
    """A model's response on one flight, next to the measurements (Figures 6, 7, 9, 10)."""

    name: str
    t: np.ndarray
    inputs: dict[str, np.ndarray]
    measured: dict[str, np.ndarray]
    simulated: dict[str, np.ndarray]
    forces_measured: dict[str, np.ndarray]
    forces_simulated: dict[str, np.ndarray]
    metrics: dict[str, dict[str, float]]
    local_params: dict[str, float]


@dataclass(frozen=True)
class Identification:
    """What [`fwid.identify`][] found: the fit(s), their modes and their metrics."""

    model: GreyBoxModel
    flights: list[str]
    fits: list[FitResult]
    estimation: list[FlightFit]
    validation: list[FlightFit] = field(default_factory=list)
    joint: bool = False
    consts: dict[str, float] = field(default_factory=dict)

    @property
    def fit(self) -> FitResult:
        return self.fits[0]

    @property
    def eigenvalues(self) -> np.ndarray:
        return eigenvalues(self.model, self.consts)

    @property
    def modes(self) -> list[dict]:
        return modes(self.eigenvalues)


def get_model(model: str | GreyBoxModel) -> GreyBoxModel:
    if isinstance(model, GreyBoxModel):
        return model
    try:
        return MODELS[model]()
    except KeyError:
        raise InputError(
            f"unknown model {model!r}: choose one of {', '.join(MODELS)} or pass a GreyBoxModel"
        ) from None


def averaged(flight: Flight, model: GreyBoxModel, cutoff: float = 5.0,
             noise_cutoff: float = 40.0, edge: float = 0.2) -> Experiment:
    """The flight's cycle-averaged part as an [`fwid.Experiment`][] for `model`.

    The zero-phase split is least reliable in the first and last few tenths of a second (the
    filter sees past the record's ends), so `edge` seconds are dropped at each end after
    filtering; the initial state is then the first remaining cycle-averaged sample.
    """
    flight.require(dict.fromkeys(list(model.inputs) + list(model.outputs)))
    avg = cycle_averaged(flight, cutoff=cutoff, noise_cutoff=noise_cutoff)
    k = int(round(edge / flight.dt))
    if flight.n - 2 * k < 50:
        k = 0
    return experiment(avg.slice(k, flight.n - k) if k else avg, model)


def evaluate(
    model: GreyBoxModel, exp: Experiment, name: str, *, refit_local: bool = True
) -> FlightFit:
    """Simulate `model` on one experiment and score it against the measurements.

    With `refit_local`, the model's flight-specific parameters (the bias terms) are first
    re-estimated on this flight, everything else held at its value: a validation flight has
    its own trim errors, which the biases exist to absorb.
    """
    local = {}
    if refit_local and model.local:
        # bias terms enter affinely: a weighted linear solve (no second estimator to compile);
        # the full ML fit of the biases otherwise
        local = refit_local_affine(model, exp)
        if local is None:
            r = fit(model.with_free(model.local), exp, names=[name], start="model")
            local = {k: float(r.model.params[k]) for k in model.local}
        model = model.with_params(local)
    xs, ys = simulate(model, exp)
    fm, fs = {}, {}
    if model.forces is not None and exp.forces is not None:
        F = np.asarray(simulate_forces(model, xs, exp))
        fm = {k: np.asarray(exp.forces[:, j]) for j, k in enumerate(model.force_names)}
        fs = {k: F[:, j] for j, k in enumerate(model.force_names)}
    z, y = np.asarray(exp.z), np.asarray(ys)
    metrics = fit_metrics(z, y, model.outputs)
    if fm:
        metrics.update(fit_metrics(np.stack(list(fm.values()), -1),
                                   np.stack(list(fs.values()), -1), list(fm)))
    return FlightFit(
        name=name, t=np.asarray(exp.t),
        inputs={k: np.asarray(exp.u[:, j]) for j, k in enumerate(model.inputs)},
        measured={k: z[:, j] for j, k in enumerate(model.outputs)},
        simulated={k: y[:, j] for j, k in enumerate(model.outputs)},
        forces_measured=fm, forces_simulated=fs, metrics=metrics, local_params=local,
    )


def _mean_model(model: GreyBoxModel, fits: Sequence[FitResult]) -> GreyBoxModel:
    values = {k: float(np.mean([float(f.model.params[k]) for f in fits])) for k in model.free}
    return model.with_params(values)


def identify(
    flights: Sequence[Flight],
    model: str | GreyBoxModel = "lon",
    *,
    validate: Sequence[Flight] = (),
    joint: bool = False,
    cutoff: float = 5.0,
    noise_cutoff: float = 40.0,
    progress: bool = False,
) -> Identification:
    """Identify the cycle-averaged model from flights, as in the paper's Section IV.

    Each flight is split (Sec. III.B) and its cycle-averaged part, inputs included, is fitted
    by output-error ML (Eqs. 10-11) from a least-squares start. Without `joint`, each flight
    gets its own fit (the paper's practice) and the summary model is the mean of their
    estimates; with `joint`, one parameter set is fitted to all flights together, each with
    its own initial state, trim and bias terms. Validation flights are simulated with the
    summary model, their bias terms re-estimated.
    """
    model = get_model(model)
    flights = list(flights)
    if not flights:
        raise InputError("no flights to identify from")
    exps = [averaged(f, model, cutoff, noise_cutoff) for f in flights]
    names = [f.name for f in flights]
    if joint or len(exps) == 1:
        fits = [fit(model, exps, names=names, progress=progress)]
        summary = fits[0].model
        estimation = []
        for i, (e, n) in enumerate(zip(exps, names)):
            estimation.append(evaluate(fits[0].flight_model(i), e, n, refit_local=False))
    else:
        fits = fit_each(model, exps, names=names, progress=progress)
        summary = _mean_model(model, fits)
        estimation = [evaluate(f.model, e, n, refit_local=False)
                      for f, e, n in zip(fits, exps, names)]
    validation = [
        evaluate(summary, averaged(f, model, cutoff, noise_cutoff), f.name)
        for f in validate
    ]
    consts = {k: float(v) for k, v in exps[0].consts.items()}
    return Identification(model=summary, flights=names, fits=fits, estimation=estimation,
                          validation=validation, joint=joint, consts=consts)
