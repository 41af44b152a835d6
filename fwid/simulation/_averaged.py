"""A flight's cycle-averaged part as the experiment the cycle-averaged models are fitted to."""

from __future__ import annotations

from ..data._flight import Flight
from ..decomposition._split import cycle_averaged, edge_samples
from ..models._greybox import GreyBoxModel
from ._experiment import Experiment, experiment


def averaged(flight: Flight, model: GreyBoxModel, cutoff: float = 5.0,
             noise_cutoff: float | None = 40.0, edge: float = 0.2) -> Experiment:
    """The flight's cycle-averaged part (Sec. III.B) as an [`fwid.Experiment`][] for `model`.

    The zero-phase split is least reliable in the first and last few tenths of a second (the
    filter sees past the record's ends), so `edge` seconds are dropped at each end after
    filtering; the initial state is then the first remaining cycle-averaged sample.
    """
    flight.require(dict.fromkeys(list(model.inputs) + list(model.outputs)))
    avg = cycle_averaged(flight, cutoff=cutoff, noise_cutoff=noise_cutoff)
    k = edge_samples(flight.n, flight.dt, edge)
    return experiment(avg.slice(k, flight.n - k) if k else avg, model)
