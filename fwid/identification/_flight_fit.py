"""A model's response on one flight next to the measurements, and its fit metrics: what every
pipeline returns per flight (Figures 6, 7, 9, 10, 12, 13, 16, 17)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .._errors import FitDivergedError
from ..estimate._equation_error import (equation_error_locals, loads_at_measured_states,
                                       measured_state_index)
from ..estimate._local import refit_local_affine
from ..estimate._fit import fit
from ..estimate._stability import GROWTH_MAX, fastest_growth
from ..estimate._warnings import quiet_fits
from ..models._greybox import GreyBoxModel
from ..simulation._buckets import pad_experiment
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate, simulate_forces
from ..validate._metrics import fit_metrics


@dataclass(frozen=True, repr=False)
class FlightFit:
    """A model's response on one flight, next to the measurements (Figures 6, 7, 9, 10).

    **Fields:**

    - `name`: the flight's name.
    - `t`: the time [s], shape `(n,)`.
    - `inputs`, `measured`, `simulated`: the inputs, the measured and the simulated outputs
      by name, perturbations from the trim.
    - `forces_measured`, `forces_simulated`: the reconstructed and the model's loads by name
      (empty when the model has no force outputs).
    - `metrics`: [`fwid.fit_metrics`][] of the outputs.
    - `local_params`: the flight-specific parameters (bias terms) used on this flight.
    """

    name: str
    t: np.ndarray
    inputs: dict[str, np.ndarray]
    measured: dict[str, np.ndarray]
    simulated: dict[str, np.ndarray]
    forces_measured: dict[str, np.ndarray]
    forces_simulated: dict[str, np.ndarray]
    metrics: dict[str, dict[str, float]]
    local_params: dict[str, float]

    def __repr__(self) -> str:
        rms = ", ".join(f"{k} {v['rms_pct']:.1f}%" for k, v in self.metrics.items())
        return (f"FlightFit({self.name!r}, {len(self.t)} samples, outputs={list(self.measured)}, "
                f"rms as % of range: {rms})")



def flight_fit(
    name: str,
    t,
    inputs: Mapping[str, np.ndarray],
    outputs: Sequence[str],
    z,
    y,
    *,
    force_names: Sequence[str] = (),
    forces_measured=None,
    forces_simulated=None,
    local: Mapping[str, float] | None = None,
) -> FlightFit:
    """A [`fwid.FlightFit`][] from measured `z` and simulated `y` outputs `(n, ny)`, and the
    measured and simulated forces `(n, nf)` when given; metrics as [`fwid.fit_metrics`][]."""
    z, y = np.asarray(z), np.asarray(y)
    metrics = fit_metrics(z, y, outputs)
    fm, fs = {}, {}
    if forces_measured is not None and forces_simulated is not None:
        Fm, F = np.asarray(forces_measured), np.asarray(forces_simulated)
        fm = {k: Fm[:, j] for j, k in enumerate(force_names)}
        fs = {k: F[:, j] for j, k in enumerate(force_names)}
        metrics.update(fit_metrics(Fm, F, force_names))
    return FlightFit(
        name=name, t=np.asarray(t), inputs=dict(inputs),
        measured={k: z[:, j] for j, k in enumerate(outputs)},
        simulated={k: y[:, j] for j, k in enumerate(outputs)},
        forces_measured=fm, forces_simulated=fs, metrics=metrics, local_params=dict(local or {}),
    )


def _grows(model: GreyBoxModel, exp: Experiment) -> bool:
    """Whether the model's open-loop simulation grows beyond `GROWTH_MAX`-fold over the
    flight (an unstable model: its simulation cannot re-estimate the biases) and its states
    are measured (so that equation error can)."""
    if measured_state_index(model) is None:
        return False  # (equation error needs the states measured)
    T = float(exp.t[-1] - exp.t[0])
    return fastest_growth(model, exp) * T > float(np.log(GROWTH_MAX))


def evaluate(
    model: GreyBoxModel, exp: Experiment, name: str, *, refit_local: bool = True,
    method: str = "output-error",
) -> FlightFit:
    """Simulate `model` on one experiment and score it against the measurements.

    With `refit_local`, the model's flight-specific parameters (the bias terms) are first
    re-estimated on this flight, everything else held at its value: a validation flight has
    its own trim errors, which the biases exist to absorb. They are re-estimated by the
    maximum likelihood of the simulated outputs, or, with `method="equation-error"` and for
    a model whose simulation grows beyond a hundredfold over the flight (which no bias could
    keep near the data), by equation error at the measured states.

    With `method="equation-error"` the loads are those the model predicts at the measured
    states (the equation-error prediction, with the flight's own load offsets); otherwise
    those along the simulated states.

    **Arguments:**

    - `model`: the [`fwid.GreyBoxModel`][] to score.
    - `exp`: the [`fwid.Experiment`][] of the flight.
    - `name`: the flight's name.
    - `refit_local`: re-estimate the bias terms on this flight first (default `True`).
    - `method`: the estimator the model came from ([`fwid.fit`][]'s `method`).

    **Returns:** a [`fwid.FlightFit`][].
    """
    n = exp.n
    padded = pad_experiment(exp)  # one of a few lengths: a new length rarely compiles
    if refit_local and model.local:
        if method == "equation-error" or _grows(model, exp):
            local = equation_error_locals(model, exp, name)
        else:
            # bias terms enter affinely: a weighted linear solve (no second estimator to
            # compile); the full ML fit of the biases otherwise
            try:
                local = refit_local_affine(model, padded)
            except FitDivergedError as exc:
                raise FitDivergedError(f"{name}: {exc} (an unstable model, or a term that "
                                       "grows without bound)") from exc
            if local is None:  # (an internal fit: its warnings are not the model's)
                with quiet_fits():
                    r = fit(model.with_free(model.local), exp, names=[name], start="model")
                local = {k: float(r.model.params[k]) for k in model.local}
        model = model.with_params(local)
    local = {k: float(model.params[k]) for k in model.local}
    with np.errstate(over="ignore", invalid="ignore"):
        xs, ys = simulate(model, padded)  # the padding, simulated after the end, is cut off
    forces = model.forces is not None and exp.forces is not None
    if forces:
        loads = (loads_at_measured_states(model, exp) if method == "equation-error"
                 else simulate_forces(model, xs, padded)[:n])
    return flight_fit(
        name, exp.t, {k: np.asarray(exp.u[:, j]) for j, k in enumerate(model.inputs)},
        model.outputs, exp.z, ys[:n], force_names=model.force_names if forces else (),
        forces_measured=exp.forces if forces else None,
        forces_simulated=loads if forces else None, local=local,
    )
