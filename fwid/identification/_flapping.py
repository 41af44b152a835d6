"""The flapping pipeline, Section V: the Fourier-series model of the flapping forces (Eq. 12)
from the flapping part of flights, least-squares start then output-error ML (Table 7), fit
metrics (Table 8), validation after phase alignment (Figures 12-13)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .._errors import InputError
from ..data._flight import Flight
from ..estimate._fit import fit
from ..estimate._problem import FitResult
from ..models._fourier import estimate_phase_offset, fourier_least_squares, fourier_model
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate
from ..validate._harmonics import harmonic_amplitudes
from ._flapping_data import (
    check_frequency_of,
    display_inputs,
    flapping_data,
    fourier_experiment,
    outputs_for,
    trimmed,
)
from ._flight_fit import FlightFit, flight_fit
from ._progress import say


def fourier_flight_fit(name, t, inputs, model, exp, local=None) -> FlightFit:
    """The Fourier model's flapping forces on one experiment, next to the measured ones."""
    _, ys = simulate(model, exp)
    return flight_fit(name, t, inputs, model.outputs, exp.z, ys, local=local)


def flapping_peaks(measured: dict, simulated: dict, dt: float, f, n: int, cutoff) -> dict:
    names = list(measured)
    am = harmonic_amplitudes(np.stack([measured[k] for k in names]), dt, f, n, cutoff=cutoff)
    ay = harmonic_amplitudes(np.stack([simulated[k] for k in names]), dt, f, n, cutoff=cutoff)
    out = {}
    for i, k in enumerate(names):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = ay[i] / am[i]
        out[k] = dict(measured=am[i].tolist(), model=ay[i].tolist(), ratio=ratio.tolist())
    return out


@dataclass(frozen=True, repr=False)
class FlappingIdentification:
    """What [`fwid.identify_flapping_model`][] found (Section V).

    **Fields:**
    - `model`: the Fourier model with the estimates (the mean over flights when each flight
      was fitted alone), in the phase frame of the first flight.
    - `flights`: the estimation flights' names.
    - `fits`: the [`fwid.FitResult`][]s (one, or one per flight).
    - `estimation`, `validation`: [`fwid.FlightFit`][]s of the flapping forces (Figs. 12-13).
    - `phase_offsets`: per flight, the phase [rad] added to its measured phase to align it
      with the model (0 for the first flight; estimated for the others, Section V.A).
    - `frequencies`: per flight, the mean measured flapping frequency [Hz].
    - `peaks`: per flight and output, the first flapping peaks, measured and model.
    - `joint`: one coefficient set fitted to all flights together.
    """

    model: GreyBoxModel
    flights: list[str]
    fits: list[FitResult]
    estimation: list[FlightFit]
    validation: list[FlightFit] = field(default_factory=list)
    phase_offsets: dict[str, float] = field(default_factory=dict)
    frequencies: dict[str, float] = field(default_factory=dict)
    peaks: dict[str, dict] = field(default_factory=dict)
    joint: bool = False

    @property
    def fit(self) -> FitResult:
        return self.fits[0]

    def __repr__(self) -> str:
        outputs = list(self.model.outputs)
        return (f"FlappingIdentification(outputs={outputs}, flights={self.flights}, "
                f"{'joint' if self.joint else 'per-flight'}, "
                f"{sum(bool(f.converged) for f in self.fits)}/{len(self.fits)} converged, "
                f"{len(self.model.free)} coefficients, "
                f"validation flights={[v.name for v in self.validation]})")



def per_flight(value, n, what):
    if value is None or isinstance(value, GreyBoxModel):
        return [value] * n
    value = list(value)
    if len(value) != n:
        raise ValueError(f"{what}: expected {n} models, got {len(value)}")
    return value


def padded(exp: Experiment) -> Experiment:
    """`exp` padded (mask 0) to the next power of two samples, at least 1024: fits of records
    of similar length (flights, their quiet starts, their manoeuvres) then share one compiled
    estimator; the static model costs little per sample."""
    n = exp.n
    m = max(1024, 1 << (n - 1).bit_length())
    if m == n:
        return exp
    k = m - n
    t = np.asarray(exp.t)
    dt = t[1] - t[0]
    tail = t[-1] + dt * np.arange(1, k + 1)
    u = np.asarray(exp.u)
    du = u[-1] - u[-2]
    return Experiment(np.concatenate([t, tail]),
                      np.concatenate([u, u[-1] + du * np.arange(1, k + 1)[:, None]]),
                      np.concatenate([np.asarray(exp.z), np.zeros((k, exp.z.shape[1]))]),
                      x0=np.zeros(0),
                      mask=np.concatenate([np.asarray(exp.mask), np.zeros(k)]))


def fit_fourier(model, exps, names, progress):
    """Least-squares start, then output-error ML ([`fwid.fit`][]), as in Section V.A."""
    exps = [padded(e) for e in exps]
    ls = fourier_least_squares(model, exps)
    return fit(model, exps, names=names, start=ls, progress=progress)


def identify_flapping_model(
    flights: Sequence[Flight],
    outputs: Sequence[str] | None = None,
    harmonics: int = 3,
    *,
    validate: Sequence[Flight] = (),
    joint: bool = False,
    cutoff: float = 5.0,
    noise_cutoff: float | None = None,
    cycle: GreyBoxModel | Sequence[GreyBoxModel] | None = None,
    validate_cycle: GreyBoxModel | Sequence[GreyBoxModel] | None = None,
    check_frequency: bool = True,
    progress: bool = False,
) -> FlappingIdentification:
    """Identify the Fourier-series model of the flapping aerodynamics, Section V.

    Each flight's flapping part (Sec. III.B) is fitted by Eq. (12) driven by the flapping
    phase (the integral of the measured `2 pi f`): ordinary least squares for the start, then
    output-error ML (Eqs. 10-11, [`fwid.fit`][]) with standard deviations (Table 7). Flights
    begin at arbitrary points of the stroke, so every flight but the first, and every
    validation flight, gets one phase offset that aligns it with the model (Section V.A);
    it is estimated, reported, and applied before fitting or scoring.

    **Arguments:**
    - `flights`: estimation flights (columns: the forces and `f`).
    - `outputs`: force/moment channels (default `X Z M`, or `Y L N` for lateral flights).
    - `harmonics`: `h` of Eq. (12) (default 3).
    - `validate`: validation flights, scored with the model after phase alignment.
    - `joint`: fit one coefficient set to all (aligned) flights; otherwise each flight is
      fitted alone and the model is the mean of their (aligned) coefficients.
    - `cutoff`, `noise_cutoff`, `cycle`: see `flapping_data`; `cycle` may be one
      model or one per flight, `validate_cycle` likewise for the validation flights.
    - `check_frequency`: cross-check the `f` column against the forces' spectrum.
    - `progress`: print what it does.

    **Returns:** a [`fwid.FlappingIdentification`][].
    """
    flights = list(flights)
    if not flights:
        raise InputError("no flights to identify the flapping model from")
    outputs = outputs_for(flights, outputs)
    model = fourier_model(outputs, harmonics)
    names = [f.name for f in flights]
    cycles = per_flight(cycle, len(flights), "cycle")
    data = [flapping_data(f, outputs, cutoff=cutoff, noise_cutoff=noise_cutoff, cycle=c)
            for f, c in zip(flights, cycles)]
    if check_frequency:
        for f, (t, _, z) in zip(flights, data):
            say(progress, check_frequency_of(f, z, outputs, trimmed(f, t)))
    exps = [fourier_experiment(t, ph, z) for t, ph, z in data]

    # The first flight fixes the phase frame; the others are aligned to it.
    first = fit_fourier(model, exps[:1], names[:1], progress)
    offsets = {names[0]: 0.0}
    for f, (t, ph, z), i in zip(flights[1:], data[1:], range(1, len(flights))):
        offsets[f.name] = estimate_phase_offset(first.model, ph, z)
        exps[i] = fourier_experiment(t, ph + offsets[f.name], z)
        say(progress, f"{f.name}: phase offset {offsets[f.name]:+.3f} rad to {names[0]}")
    if len(flights) == 1:
        fits = [first]
        summary = first.model
    elif joint:
        fits = [fit_fourier(model, exps, names, progress)]
        summary = fits[0].model
    else:
        fits = [first] + [fit_fourier(model, [e], [n], progress)
                          for e, n in zip(exps[1:], names[1:])]
        summary = model.with_params({k: float(np.mean([float(r.model.params[k]) for r in fits]))
                                     for k in model.free})
    fmean = {f.name: float(np.mean(np.asarray(f["f"]))) for f in flights}
    estimation, peaks = [], {}
    for i, (f, e, (t, _, _)) in enumerate(zip(flights, exps, data)):
        m = fits[i].model if (len(fits) > 1) else summary
        sl = trimmed(f, t)
        ff = fourier_flight_fit(f.name, t, display_inputs(f, outputs, cutoff, e, sl), m, e,
                         {"phase_offset": offsets[f.name]})
        estimation.append(ff)
        peaks[f.name] = flapping_peaks(ff.measured, ff.simulated, f.dt, np.asarray(f["f"])[sl],
                               harmonics, None)

    validation = []
    vcycles = per_flight(validate_cycle, len(validate), "validate_cycle")
    for f, c in zip(validate, vcycles):
        t, ph, z = flapping_data(f, outputs, cutoff=cutoff, noise_cutoff=noise_cutoff, cycle=c)
        sl = trimmed(f, t)
        if check_frequency:
            say(progress, check_frequency_of(f, z, outputs, sl))
        d = estimate_phase_offset(summary, ph, z)
        offsets[f.name] = d
        fmean[f.name] = float(np.mean(np.asarray(f["f"])))
        say(progress, f"{f.name}: validation phase offset {d:+.3f} rad")
        e = fourier_experiment(t, ph + d, z)
        ff = fourier_flight_fit(f.name, t, display_inputs(f, outputs, cutoff, e, sl), summary, e,
                         {"phase_offset": d})
        validation.append(ff)
        peaks[f.name] = flapping_peaks(ff.measured, ff.simulated, f.dt, np.asarray(f["f"])[sl],
                               harmonics, None)
    return FlappingIdentification(
        model=summary, flights=names, fits=fits, estimation=estimation,
        validation=validation, phase_offsets=offsets, frequencies=fmean, peaks=peaks,
        joint=bool(joint and len(flights) > 1),
    )
