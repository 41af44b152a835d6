"""The combined pipeline, Section VI: the cycle-averaged model (Section IV) plus the Fourier
model (Section V) in the EOM (Eqs. 13-15), simulated over whole flights (Figures 15-17)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from .._errors import FlightDataError, InputError
from ..data._flight import Flight
from ..decomposition._filters import lowpass
from ..estimate._local import refit_local_affine
from ..models._combined import combined, force_parts
from ..models._fourier import LAT_OUTPUTS, LON_OUTPUTS
from ..models._greybox import GreyBoxModel
from ..simulation._averaged import averaged
from ..simulation._experiment import Experiment, experiment
from ..simulation._simulate import simulate
from ..validate._modes import eigenvalues
from ._cycle_averaged import Identification, identify
from ._flapping import FlappingIdentification, flapping_peaks, identify_flapping_model
from ._flapping_data import flight_axis, phase_of, slow
from ._flight_fit import FlightFit, evaluate, flight_fit
from ._progress import say


@dataclass(frozen=True, repr=False)
class CombinedIdentification:
    """What [`fwid.identify_combined`][] found (Section VI).

    **Fields:**
    - `model`: the combined model (Eqs. 13-15 in Eq. 7): the summary cycle-averaged model
      plus the Fourier model.
    - `cycle`: the cycle-averaged [`fwid.Identification`][] (Section IV), or `None` when a
      cycle-averaged model was given.
    - `flapping`: the [`fwid.FlappingIdentification`][] of the Fourier part (Section V).
    - `estimation`, `validation`: [`fwid.FlightFit`][]s of the full simulation: states and
      total forces, measured vs combined model (Figures 16, 17).
    - `peaks`: per flight and signal, the first flapping peaks, measured vs model.
    - `parts`: per flight, the two force terms `{"TA": {X: ..}, "TV": {X: ..}}` (Figure 15).
    - `frequencies`: per flight, the mean flapping frequency [Hz].
    - `flights`: the estimation flights' names; `consts`: the first flight's trim and vehicle.
    - `cycle_model`: the summary cycle-averaged model inside `model`.
    """

    model: GreyBoxModel
    cycle: Identification | None
    flapping: FlappingIdentification
    estimation: list[FlightFit]
    validation: list[FlightFit] = field(default_factory=list)
    peaks: dict[str, dict] = field(default_factory=dict)
    parts: dict[str, dict] = field(default_factory=dict)
    frequencies: dict[str, float] = field(default_factory=dict)
    flights: list[str] = field(default_factory=list)
    consts: dict[str, float] = field(default_factory=dict)
    cycle_model: GreyBoxModel | None = None

    @property
    def eigenvalues(self) -> np.ndarray:
        """The eigenvalues of the cycle-averaged part (the Fourier part adds no dynamics)."""
        return eigenvalues(self.cycle_model or self.model, self.consts)

    def __repr__(self) -> str:
        return (f"CombinedIdentification(model={self.model.name!r}, flights={self.flights}, "
                f"cycle-averaged {len((self.cycle_model or self.model).free)} + flapping "
                f"{len(self.flapping.model.free)} parameters, "
                f"validation flights={[v.name for v in self.validation]})")



def _cycle_models(cycle: Identification) -> list[GreyBoxModel]:
    """The cycle-averaged model of each estimation flight, with that flight's biases."""
    if len(cycle.fits) == 1:
        return [cycle.fits[0].flight_model(i) for i in range(len(cycle.flights))]
    return [r.model for r in cycle.fits]


def _local_of(model: GreyBoxModel, flight: Flight, cutoff: float) -> dict:
    """A flight's bias terms for a given cycle-averaged model (ML, all else held)."""
    if not model.local:
        return {}
    exp = averaged(flight, model, cutoff)
    local = refit_local_affine(model, exp)
    return local if local is not None else evaluate(model, exp, flight.name).local_params


def _validate_cycle(cycle: Identification, flights, cutoff) -> Identification:
    """The cycle-averaged validation of [`fwid.identify`][] (summary model, bias terms
    re-estimated per flight), with the biases from `fwid.estimate.refit_local_affine`."""
    out = []
    model = cycle.model
    for f in flights:
        exp = averaged(f, model, cutoff)
        local = refit_local_affine(model, exp) if model.local else {}
        if local is None:  # not affine in the biases: the general (slower) path
            out.append(evaluate(model, exp, f.name))
            continue
        ff = evaluate(model.with_params(local), exp, f.name, refit_local=False)
        out.append(dataclasses.replace(ff, local_params=local))
    return dataclasses.replace(cycle, validation=out)


def combined_experiment(
    flight: Flight,
    model: GreyBoxModel,
    *,
    phase_offset: float = 0.0,
    cutoff: float = 5.0,
    noise_cutoff: float | None = None,
) -> Experiment:
    """An [`fwid.Experiment`][] for a combined model: the cycle-averaged control input and the
    (aligned) flapping phase as inputs, the measured states (with their flapping part) as
    outputs and initial state, the measured forces for comparison.

    The control input is cycle-averaged as for the cycle-averaged model (its ripple at the
    flapping frequency is flapping content, carried by the Fourier series).
    """
    cycle_inputs = [c for c in model.inputs if c != "phase"]
    cols = {c: slow(flight, c, cutoff) + np.asarray(flight.trim_value(c)) for c in cycle_inputs}
    cols["phase"] = phase_of(flight) + phase_offset
    if noise_cutoff is not None:
        for c in tuple(model.states) + tuple(model.force_names):
            if c in flight:
                cols[c] = np.asarray(lowpass(flight[c], flight.dt, noise_cutoff))
    return experiment(flight.with_columns(**cols), model)


def simulate_flight(model, flight, offset, cutoff, noise_cutoff, harmonics):
    """Simulate the combined model over one whole flight: its fit, flapping peaks and the two
    force terms of Eq. (13)."""
    exp = combined_experiment(flight, model, phase_offset=offset, cutoff=cutoff,
                              noise_cutoff=noise_cutoff)
    xs, ys = simulate(model, exp)
    if not bool(jnp.all(jnp.isfinite(xs))):
        raise FlightDataError(
            f"{flight.name}: the combined simulation blew up; check the identified "
            "cycle-averaged model's eigenvalues (an unstable mode) and the trim"
        )
    F = np.asarray(jax.vmap(lambda x, u: model.forces(x, u, model.params, exp.consts))(xs, exp.u))
    ta, tv = (np.asarray(a) for a in force_parts(model, xs, exp))
    has_forces = exp.forces is not None
    ff = flight_fit(
        flight.name, exp.t, {k: np.asarray(exp.u[:, j]) for j, k in enumerate(model.inputs)},
        model.outputs, exp.z, ys, force_names=model.force_names if has_forces else (),
        forces_measured=exp.forces if has_forces else None, forces_simulated=F,
        local={**{k: float(model.params[k]) for k in model.local}, "phase_offset": float(offset)},
    )
    peaks = flapping_peaks({**ff.measured, **ff.forces_measured},
                           {**ff.simulated, **ff.forces_simulated}, flight.dt, flight["f"],
                           harmonics, cutoff)
    parts = {"TA": {k: ta[:, j] for j, k in enumerate(model.force_names)},
             "TV": {k: tv[:, j] for j, k in enumerate(model.force_names)}}
    return ff, peaks, parts


def identify_combined(
    flights: Sequence[Flight],
    axis: str | None = None,
    harmonics: int = 3,
    *,
    validate: Sequence[Flight] = (),
    joint: bool = False,
    cutoff: float = 5.0,
    noise_cutoff: float | None = None,
    subtract_cycle: bool = True,
    cycle: Identification | GreyBoxModel | None = None,
    progress: bool = False,
) -> CombinedIdentification:
    """Identify and simulate the full time-varying model, Section VI (Eqs. 13-15 in Eq. 7).

    1. The cycle-averaged model is identified on the cycle-averaged data (Section IV,
       [`fwid.identify`][]), unless given; the validation flights' bias terms are
       re-estimated (all else held).
    2. The Fourier model is identified on the flapping part of the forces
       ([`fwid.identify_flapping_model`][]); with `subtract_cycle`, of the forces less the
       cycle-averaged model's forces on the measured states, so that Eq. (13)'s two terms
       do not both carry the state-driven flapping response.
    3. Both are summed into the EOM and simulated with diffrax (RK4 at the sample step) over
       each whole flight from its measured initial state, with the measured flapping phase
       as an input (aligned per flight); the flapping then shows in the states.

    **Arguments:**
    - `flights`, `validate`: estimation and validation flights.
    - `axis`: `"lon"` or `"lat"` (default: from the flights' control input).
    - `harmonics`: `h` of Eq. (12).
    - `joint`: one parameter set fitted to all flights (both sub-models).
    - `cutoff`: the cycle-averaged / flapping split [Hz]; `noise_cutoff`: the noise low-pass
      of the flapping data and of the measurements the simulation is compared with (`None`).
    - `subtract_cycle`: see step 2.
    - `cycle`: skip step 1: an [`fwid.Identification`][] made by [`fwid.identify`][] from
      the same flights, or an identified cycle-averaged model (e.g. from notebook 01), whose
      bias terms are then re-estimated on every flight.
    - `progress`: print what it does.

    **Returns:** a [`fwid.CombinedIdentification`][].
    """
    flights, validate = list(flights), list(validate)
    if not flights:
        raise InputError("no flights to identify the combined model from")
    axis = axis or flight_axis(flights[0])
    outputs = LAT_OUTPUTS if axis == "lat" else LON_OUTPUTS
    for f in flights + validate:
        f.require(outputs + ("f",))
    if isinstance(cycle, GreyBoxModel):
        summary = cycle
        cycle = None
        cycles = [summary.with_params(_local_of(summary, f, cutoff)) for f in flights]
        vcycles = [summary.with_params(_local_of(summary, f, cutoff)) for f in validate]
    else:
        if cycle is None:
            say(progress, f"cycle-averaged ({axis}) model, Section IV")
            cycle = identify(flights, axis, joint=joint, cutoff=cutoff, progress=progress)
        elif list(cycle.flights) != [f.name for f in flights]:
            raise InputError(f"the cycle-averaged identification is of {cycle.flights}, not "
                             f"of the flights given ({[f.name for f in flights]})")
        done = [v.name for v in cycle.validation]
        if validate and done != [f.name for f in validate]:
            cycle = _validate_cycle(cycle, validate, cutoff)
        summary = cycle.model
        cycles = _cycle_models(cycle)
        vcycles = [summary.with_params(v.local_params) for v in cycle.validation]
    say(progress, "flapping (Fourier) model, Section V")
    flap = identify_flapping_model(
        flights, outputs, harmonics, validate=validate, joint=joint, cutoff=cutoff,
        noise_cutoff=noise_cutoff, cycle=cycles if subtract_cycle else None,
        validate_cycle=vcycles if subtract_cycle else None, progress=progress,
    )
    say(progress, "combined model, Section VI: simulating")
    estimation, validation, peaks, parts, freqs = [], [], {}, {}, {}
    for group, fl, cms in ((estimation, flights, cycles), (validation, validate, vcycles)):
        for f, cm in zip(fl, cms):
            model = combined(cm, flap.model)
            ff, pk, pt = simulate_flight(model, f, flap.phase_offsets[f.name], cutoff,
                                          noise_cutoff, harmonics)
            group.append(ff)
            peaks[f.name], parts[f.name] = pk, pt
            freqs[f.name] = flap.frequencies[f.name]
    consts = {k: float(v) for k, v in experiment(flights[0], summary).consts.items()}
    return CombinedIdentification(
        model=combined(summary, flap.model), cycle=cycle, flapping=flap,
        estimation=estimation, validation=validation, peaks=peaks, parts=parts,
        frequencies=freqs, flights=[f.name for f in flights], consts=consts,
        cycle_model=summary,
    )
