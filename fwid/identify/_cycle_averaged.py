"""The cycle-averaged pipeline (Section IV): flights -> cycle-averaged data -> output-error
fit (Eqs. 10-11) -> modes and validation."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .._errors import InputError
from ..data._flight import Flight
from ..estimate._each import fit_each
from ..estimate._output_error import FitResult, fit
from ..models._delfly import lateral, longitudinal
from ..models._greybox import GreyBoxModel
from ..simulate._averaged import averaged
from ..validate._modes import eigenvalues, modes
from ._flight_fit import FlightFit, evaluate

MODELS = {"lon": longitudinal, "lat": lateral}


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
