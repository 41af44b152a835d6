"""The flapping (time-varying) and combined pipelines: Sections V and VI of the paper.

- [`fwid.identify_flapping_model`][]: the Fourier-series model of the flapping forces (Eq. 12)
  from the flapping part of flights, least-squares start then output-error ML (Table 7), fit
  metrics (Table 8), validation after phase alignment (Figures 12-13).
- [`fwid.steady_vs_manoeuvre`][]: the same fit on a flight's quiet start and on its manoeuvre
  (Figures 12 and 14).
- [`fwid.identify_combined`][]: the cycle-averaged model (Section IV) plus the Fourier model
  in the EOM (Eqs. 13-15), simulated over whole flights (Figures 15-17).
- `identify_flapping(args, flights, validate)`: the `fwid identify --model flap|combined`
  command.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ._errors import FlightDataError, InputError
from ._identify import FlightFit, Identification, averaged, evaluate, identify
from .data._flight import Flight
from .data._trim import input_column
from .decompose._filters import lowpass
from .decompose._frequency import check_flapping_frequency, flapping_phase
from .decompose._split import flapping_part
from .estimate._local import refit_local_affine
from .estimate._output_error import FitResult, fit
from .models._combined import combined, force_parts
from .models._fourier import (
    LAT_OUTPUTS,
    LON_OUTPUTS,
    estimate_phase_offset,
    fourier_least_squares,
    fourier_model,
    fourier_structure,
)
from .models._greybox import GreyBoxModel
from .report._json import add_validation, pooled_metrics
from .report._spectra import harmonic_amplitudes
from .simulate._experiment import Experiment, experiment
from .simulate._simulate import simulate
from .validate._metrics import fit_metrics
from .validate._modes import eigenvalues

# -- helpers ---------------------------------------------------------------------------------


def flight_axis(flight: Flight) -> str:
    """`"lon"` or `"lat"`: the axis a flight's manoeuvre excites (its varying control input),
    or, without one, the axis whose forces it carries (longitudinal when both)."""
    col = input_column(flight.columns, np.asarray(flight.t))
    if col == "dr":
        return "lat"
    if col is None and not all(c in flight for c in LON_OUTPUTS) and all(
        c in flight for c in LAT_OUTPUTS
    ):
        return "lat"
    return "lon"


def _outputs_for(flights: Sequence[Flight], outputs) -> tuple[str, ...]:
    if outputs is not None:
        return tuple(outputs)
    return LAT_OUTPUTS if flight_axis(flights[0]) == "lat" else LON_OUTPUTS


def _input_name(outputs) -> str:
    return "dr" if tuple(outputs) == LAT_OUTPUTS else "de"


def _phase(flight: Flight) -> np.ndarray:
    return np.asarray(flapping_phase(flight["f"], flight.dt))


def _check_frequency(flight: Flight, z: np.ndarray, outputs, sl: slice) -> str:
    """Cross-check the `f` column against the flapping forces; fine if any output agrees."""
    first = None
    f = np.asarray(flight["f"])[sl]
    for j in range(z.shape[1]):
        try:
            return check_flapping_frequency(f, z[:, j], flight.dt, name=flight.name)
        except FlightDataError as e:
            first = first or e
    raise first


def _slow(flight: Flight, col: str, cutoff: float) -> np.ndarray:
    """The cycle-averaged perturbation of one column (the input as the models see it)."""
    return np.asarray(lowpass(flight.perturbation(col), flight.dt, cutoff, order=6))


def _cycle_forces(cycle: GreyBoxModel, flight: Flight, cutoff: float) -> np.ndarray:
    """`F_TA` of Eqs. (13)-(15) on the measured states: what the cycle-averaged model already
    explains of the forces, including the part driven by the flapping in the states."""
    flight.require(cycle.states)
    xs = jnp.stack([flight.perturbation(c) for c in cycle.states], axis=-1)
    us = jnp.stack([jnp.asarray(_slow(flight, c, cutoff)) for c in cycle.inputs], axis=-1)
    consts = experiment(flight, cycle).consts
    return np.asarray(jax.vmap(lambda x, u: cycle.forces(x, u, cycle.params, consts))(xs, us))


def flapping_data(
    flight: Flight,
    outputs: Sequence[str] = LON_OUTPUTS,
    *,
    cutoff: float = 5.0,
    noise_cutoff: float | None = None,
    cycle: GreyBoxModel | None = None,
    edge: float = 0.2,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The time, phase and flapping forces of one flight: what Eq. (12) is fitted to.

    **Arguments:**
    - `flight`: a flight with the force columns and the flapping frequency `f`.
    - `outputs`: the force/moment columns.
    - `cutoff`: the split between the cycle-averaged and the flapping part [Hz] (Sec. III.B).
    - `noise_cutoff`: the noise low-pass [Hz] (the paper: 40 Hz), or `None`. The default is
      none: the Fourier series only takes what is at the harmonics, so noise does not bias it,
      whereas a 40 Hz low-pass would take ~35 % off a third harmonic near 37 Hz.
    - `cycle`: an identified cycle-averaged model; when given, its forces on the measured
      states (`F_TA`) are taken off first, so that the flapping part holds only `F_TV` and
      Eqs. (13)-(15) do not count the state-driven part of the flapping forces twice.
    - `edge`: seconds dropped at each end after filtering, where the zero-phase split sees
      past the record's ends (as for the cycle-averaged data); none for very short flights.

    Noise on the `f` column integrates into a random walk of the phase (white noise of
    0.02 Hz rms at 200 Hz drifts it by ~0.02 rad rms over 4.5 s), which the coefficients'
    standard deviations do not include.

    **Returns:** `(t, phase, z)`: the time `(m,)` [s], the flapping phase `(m,)` [rad] (the
    integral of `2 pi f` from the flight's first sample) and the flapping forces
    `(m, outputs)`, with `m = n - 2 round(edge / dt)`.
    """
    flight.require(tuple(outputs) + ("f",))
    if cycle is not None:
        ta = _cycle_forces(cycle, flight, cutoff)
        cols = {k: flight.perturbation(k) - ta[:, cycle.force_names.index(k)]
                for k in outputs if k in cycle.force_names}
        flight = flight.with_columns(**cols)
    part = flapping_part(flight, cutoff=cutoff, noise_cutoff=noise_cutoff)
    z = np.stack([np.asarray(part[k]) for k in outputs], axis=-1)
    k = _edge(flight, edge)
    sl = slice(k, flight.n - k)
    return np.asarray(flight.t)[sl], _phase(flight)[sl], z[sl]


def _edge(flight: Flight, edge: float) -> int:
    k = int(round(edge / flight.dt))
    return k if flight.n - 2 * k >= 50 else 0


def _trimmed(flight: Flight, t: np.ndarray) -> slice:
    """The samples of `flight` that `flapping_data` kept (`t` its time)."""
    k = (flight.n - t.shape[0]) // 2
    return slice(k, k + t.shape[0])


def _experiment(t, phase, z) -> Experiment:
    return Experiment(t, np.asarray(phase)[:, None], z, x0=np.zeros(0))


def _flight_fit(name, t, inputs, model, exp, local=None) -> FlightFit:
    _, ys = simulate(model, exp)
    z, y = np.asarray(exp.z), np.asarray(ys)
    return FlightFit(
        name=name, t=np.asarray(t), inputs=inputs,
        measured={k: z[:, j] for j, k in enumerate(model.outputs)},
        simulated={k: y[:, j] for j, k in enumerate(model.outputs)},
        forces_measured={}, forces_simulated={},
        metrics=fit_metrics(z, y, model.outputs), local_params=dict(local or {}),
    )


def _peaks(measured: dict, simulated: dict, dt: float, f, n: int, cutoff) -> dict:
    names = list(measured)
    am = harmonic_amplitudes(np.stack([measured[k] for k in names]), dt, f, n, cutoff=cutoff)
    ay = harmonic_amplitudes(np.stack([simulated[k] for k in names]), dt, f, n, cutoff=cutoff)
    out = {}
    for i, k in enumerate(names):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = ay[i] / am[i]
        out[k] = dict(measured=am[i].tolist(), model=ay[i].tolist(), ratio=ratio.tolist())
    return out


def _say(progress, msg):
    if progress:
        print(f"fwid: {msg}", flush=True)


# -- Section V: the Fourier model ------------------------------------------------------------


@dataclass(frozen=True)
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


def _per_flight(value, n, what):
    if value is None or isinstance(value, GreyBoxModel):
        return [value] * n
    value = list(value)
    if len(value) != n:
        raise ValueError(f"{what}: expected {n} models, got {len(value)}")
    return value


def _padded(exp: Experiment) -> Experiment:
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


def _fit_fourier(model, exps, names, progress):
    """Least-squares start, then output-error ML ([`fwid.fit`][]), as in Section V.A."""
    exps = [_padded(e) for e in exps]
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
    - `cutoff`, `noise_cutoff`, `cycle`: see [`fwid.flapping_data`][]; `cycle` may be one
      model or one per flight, `validate_cycle` likewise for the validation flights.
    - `check_frequency`: cross-check the `f` column against the forces' spectrum.
    - `progress`: print what it does.

    **Returns:** a [`fwid.FlappingIdentification`][].
    """
    flights = list(flights)
    if not flights:
        raise InputError("no flights to identify the flapping model from")
    outputs = _outputs_for(flights, outputs)
    model = fourier_model(outputs, harmonics)
    names = [f.name for f in flights]
    cycles = _per_flight(cycle, len(flights), "cycle")
    data = [flapping_data(f, outputs, cutoff=cutoff, noise_cutoff=noise_cutoff, cycle=c)
            for f, c in zip(flights, cycles)]
    if check_frequency:
        for f, (t, _, z) in zip(flights, data):
            _say(progress, _check_frequency(f, z, outputs, _trimmed(f, t)))
    exps = [_experiment(t, ph, z) for t, ph, z in data]

    # The first flight fixes the phase frame; the others are aligned to it.
    first = _fit_fourier(model, exps[:1], names[:1], progress)
    offsets = {names[0]: 0.0}
    for f, (t, ph, z), i in zip(flights[1:], data[1:], range(1, len(flights))):
        offsets[f.name] = estimate_phase_offset(first.model, ph, z)
        exps[i] = _experiment(t, ph + offsets[f.name], z)
        _say(progress, f"{f.name}: phase offset {offsets[f.name]:+.3f} rad to {names[0]}")
    if len(flights) == 1:
        fits = [first]
        summary = first.model
    elif joint:
        fits = [_fit_fourier(model, exps, names, progress)]
        summary = fits[0].model
    else:
        fits = [first] + [_fit_fourier(model, [e], [n], progress)
                          for e, n in zip(exps[1:], names[1:])]
        summary = model.with_params({k: float(np.mean([float(r.model.params[k]) for r in fits]))
                                     for k in model.free})
    fmean = {f.name: float(np.mean(np.asarray(f["f"]))) for f in flights}
    estimation, peaks = [], {}
    for i, (f, e, (t, _, _)) in enumerate(zip(flights, exps, data)):
        m = fits[i].model if (len(fits) > 1) else summary
        sl = _trimmed(f, t)
        ff = _flight_fit(f.name, t, _display_inputs(f, outputs, cutoff, e, sl), m, e,
                         {"phase_offset": offsets[f.name]})
        estimation.append(ff)
        peaks[f.name] = _peaks(ff.measured, ff.simulated, f.dt, np.asarray(f["f"])[sl],
                               harmonics, None)

    validation = []
    vcycles = _per_flight(validate_cycle, len(validate), "validate_cycle")
    for f, c in zip(validate, vcycles):
        t, ph, z = flapping_data(f, outputs, cutoff=cutoff, noise_cutoff=noise_cutoff, cycle=c)
        sl = _trimmed(f, t)
        if check_frequency:
            _say(progress, _check_frequency(f, z, outputs, sl))
        d = estimate_phase_offset(summary, ph, z)
        offsets[f.name] = d
        fmean[f.name] = float(np.mean(np.asarray(f["f"])))
        _say(progress, f"{f.name}: validation phase offset {d:+.3f} rad")
        e = _experiment(t, ph + d, z)
        ff = _flight_fit(f.name, t, _display_inputs(f, outputs, cutoff, e, sl), summary, e,
                         {"phase_offset": d})
        validation.append(ff)
        peaks[f.name] = _peaks(ff.measured, ff.simulated, f.dt, np.asarray(f["f"])[sl],
                               harmonics, None)
    return FlappingIdentification(
        model=summary, flights=names, fits=fits, estimation=estimation,
        validation=validation, phase_offsets=offsets, frequencies=fmean, peaks=peaks,
        joint=bool(joint and len(flights) > 1),
    )


def _display_inputs(flight, outputs, cutoff, exp, sl: slice) -> dict:
    """The cycle-averaged control input (for the paper's scaled input) and the phase."""
    out = {}
    col = _input_name(outputs)
    if col in flight:
        out[col] = _slow(flight, col, cutoff)[sl]
    out["phase"] = np.asarray(exp.u[:, 0])
    return out


# -- Figures 12 and 14: steady flight vs manoeuvre -------------------------------------------


@dataclass(frozen=True)
class SteadyVsManoeuvre:
    """The flapping model fitted to a flight's quiet start and to its manoeuvre (Figs. 12, 14).

    **Fields:**
    - `flight`: the flight's name; `split`: the first-input index where the two parts meet.
    - `steady`, `manoeuvre`: [`fwid.FlightFit`][]s of the two parts, each with its own model.
    - `fits`: the two [`fwid.FitResult`][]s (steady, manoeuvre).
    - `summary`: per part and output: `rms`, `rms_pct` (Table 8) and `nonharmonic_pct`, the
      share (in %) of the data's energy in the flapping band that is not at the harmonics,
      i.e. that no periodic series in the flapping phase can reproduce.
    - `frequency`: the mean flapping frequency [Hz].
    """

    flight: str
    split: int
    steady: FlightFit
    manoeuvre: FlightFit
    fits: tuple[FitResult, FitResult]
    summary: dict[str, dict[str, dict[str, float]]]
    frequency: float


def nonharmonic_share(
    z: np.ndarray, y: np.ndarray, dt: float, band: tuple[float, float]
) -> np.ndarray:
    """`100 E(z - y) / E(z)` per column, energies taken within `band` [Hz] (Parseval on the
    FFT): with `y` the fitted Fourier series, the share of the flapping-band energy that is
    not at the harmonics."""
    z, y = np.asarray(z, float), np.asarray(y, float)
    freqs = np.fft.rfftfreq(z.shape[0], dt)
    sel = (freqs >= band[0]) & (freqs <= band[1])
    ez = np.sum(np.abs(np.fft.rfft(z, axis=0)[sel]) ** 2, axis=0)
    er = np.sum(np.abs(np.fft.rfft(z - y, axis=0)[sel]) ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 100.0 * er / ez


def steady_vs_manoeuvre(
    flight: Flight,
    outputs: Sequence[str] | None = None,
    harmonics: int = 3,
    *,
    cutoff: float = 5.0,
    noise_cutoff: float | None = None,
    split: int | None = None,
    min_cycles: float = 5.0,
    progress: bool = False,
) -> SteadyVsManoeuvre:
    """Fit the flapping model on the quiet start and on the manoeuvre of one flight.

    The paper (Section V.B, Figures 12 and 14) finds the flapping forces highly periodic in
    steady flight and less so once the elevator moves, a hint of coupling between the time
    scales. The flapping part is taken over the whole flight (no filter edges at the split),
    then cut at `Flight.first_input`; each part gets its own least-squares + ML fit.

    **Arguments:**
    - `flight`: the flight (with a quiet start before its first input).
    - `outputs`, `harmonics`, `cutoff`, `noise_cutoff`: as [`fwid.identify_flapping_model`][].
    - `split`: the sample where the manoeuvre starts (default `flight.first_input`).
    - `min_cycles`: the fewest flapping cycles each part must hold.

    **Returns:** a [`fwid.SteadyVsManoeuvre`][].

    **Raises:** [`fwid.InputError`][] when either part is shorter than `min_cycles` cycles.
    """
    outputs = _outputs_for([flight], outputs)
    split = flight.first_input if split is None else int(split)
    t, ph, z = flapping_data(flight, outputs, cutoff=cutoff, noise_cutoff=noise_cutoff)
    sl_all = _trimmed(flight, t)
    k = split - sl_all.start  # the split in the trimmed record
    fbar = float(np.mean(np.asarray(flight["f"])))
    need = int(np.ceil(min_cycles / (fbar * flight.dt)))
    if k < need or t.shape[0] - k < need:
        raise InputError(
            f"{flight.name}: the quiet start ({max(k, 0)} samples) and the manoeuvre "
            f"({t.shape[0] - max(k, 0)} samples), less {sl_all.start} filter-edge samples at "
            f"each end, must each hold at least {min_cycles:g} flapping cycles ({need} samples)"
        )
    model = fourier_model(outputs, harmonics)
    full_inputs = _display_inputs(flight, outputs, cutoff, _experiment(t, ph, z), sl_all)
    parts, fits, summary = [], [], {}
    fmax = min((harmonics + 0.5) * float(np.max(np.asarray(flight["f"]))), 0.5 / flight.dt)
    if noise_cutoff is not None:
        fmax = min(fmax, noise_cutoff)
    for label, sl in (("steady", slice(0, k)), ("manoeuvre", slice(k, None))):
        e = _experiment(t[sl], ph[sl], z[sl])
        r = _fit_fourier(model, [e], [f"{flight.name}[{label}]"], progress)
        inputs = {kk: v[sl] for kk, v in full_inputs.items()}
        ff = _flight_fit(f"{flight.name} ({label})", t[sl], inputs, r.model, e)
        share = nonharmonic_share(np.asarray(e.z), np.stack(list(ff.simulated.values()), -1),
                                  flight.dt, (cutoff, fmax))
        summary[label] = {
            o: dict(rms=ff.metrics[o]["rms"], rms_pct=ff.metrics[o]["rms_pct"],
                    nonharmonic_pct=float(share[j]))
            for j, o in enumerate(outputs)
        }
        parts.append(ff)
        fits.append(r)
    return SteadyVsManoeuvre(flight=flight.name, split=split, steady=parts[0],
                             manoeuvre=parts[1],
                             fits=(fits[0], fits[1]), summary=summary, frequency=fbar)


# -- Section VI: the combined model ----------------------------------------------------------


@dataclass(frozen=True)
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
    cols = {c: _slow(flight, c, cutoff) + np.asarray(flight.trim_value(c)) for c in cycle_inputs}
    cols["phase"] = _phase(flight) + phase_offset
    if noise_cutoff is not None:
        for c in tuple(model.states) + tuple(model.force_names):
            if c in flight:
                cols[c] = np.asarray(lowpass(flight[c], flight.dt, noise_cutoff))
    return experiment(flight.with_columns(**cols), model)


def _simulate_flight(model, flight, offset, cutoff, noise_cutoff, harmonics):
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
    z, y = np.asarray(exp.z), np.asarray(ys)
    Fm = np.asarray(exp.forces) if exp.forces is not None else None
    metrics = fit_metrics(z, y, model.outputs)
    fm, fs = {}, {}
    if Fm is not None:
        fm = {k: Fm[:, j] for j, k in enumerate(model.force_names)}
        fs = {k: F[:, j] for j, k in enumerate(model.force_names)}
        metrics.update(fit_metrics(Fm, F, model.force_names))
    inputs = {k: np.asarray(exp.u[:, j]) for j, k in enumerate(model.inputs)}
    ff = FlightFit(
        name=flight.name, t=np.asarray(exp.t), inputs=inputs,
        measured={k: z[:, j] for j, k in enumerate(model.outputs)},
        simulated={k: y[:, j] for j, k in enumerate(model.outputs)},
        forces_measured=fm, forces_simulated=fs, metrics=metrics,
        local_params={**{k: float(model.params[k]) for k in model.local},
                      "phase_offset": float(offset)},
    )
    peaks = _peaks({**ff.measured, **fm}, {**ff.simulated, **fs}, flight.dt, flight["f"],
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
            _say(progress, f"cycle-averaged ({axis}) model, Section IV")
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
    _say(progress, "flapping (Fourier) model, Section V")
    flap = identify_flapping_model(
        flights, outputs, harmonics, validate=validate, joint=joint, cutoff=cutoff,
        noise_cutoff=noise_cutoff, cycle=cycles if subtract_cycle else None,
        validate_cycle=vcycles if subtract_cycle else None, progress=progress,
    )
    _say(progress, "combined model, Section VI: simulating")
    estimation, validation, peaks, parts, freqs = [], [], {}, {}, {}
    for group, fl, cms in ((estimation, flights, cycles), (validation, validate, vcycles)):
        for f, cm in zip(fl, cms):
            model = combined(cm, flap.model)
            ff, pk, pt = _simulate_flight(model, f, flap.phase_offsets[f.name], cutoff,
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


# -- reports ---------------------------------------------------------------------------------


def _params(r: FitResult) -> dict:
    return {k: v for k, v in r.table().items() if "@" not in k}


def _fit_info(r: FitResult, outputs) -> dict:
    return {"converged": bool(r.converged), "passes": int(r.passes),
            "gauss_newton_steps": int(r.steps), "cost": float(r.cost),
            "R": np.asarray(r.R), "outputs": list(outputs)}


def flapping_report(ident: FlappingIdentification, steady=None) -> dict:
    """The `report.json` of `fwid identify --model flap` (CONTRACTS section 3), as a dict.

    `parameters` holds Table 7 (`value`, `std`, ...), `metrics` Table 8 per output (pooled over
    flights); `eigenvalues` is empty (a Fourier series has no dynamics). Extra keys:
    `phase_offsets`, `flapping_frequency`, `peaks`, and `steady_vs_manoeuvre` when given.
    """
    outputs, harmonics = fourier_structure(ident.model)
    report = {
        "model": "flap",
        "flights": list(ident.flights),
        "joint": ident.joint,
        "outputs": list(outputs),
        "harmonics": harmonics,
        "parameters": {},
        "eigenvalues": [],
        "metrics": {"estimation": pooled_metrics(ident.estimation)},
        "phase_offsets": dict(ident.phase_offsets),
        "flapping_frequency": dict(ident.frequencies),
        "peaks": ident.peaks,
        "units": "SI: N, N m; phase offsets in rad; rms in the output's unit",
    }
    if len(ident.fits) == 1:
        report["parameters"] = _params(ident.fit)
        report["correlation"] = {"names": list(ident.fit.names),
                                 "matrix": np.asarray(ident.fit.corr)}
        report["fit"] = _fit_info(ident.fit, outputs)
    else:
        per = [{"flight": est.name, "parameters": _params(r), "eigenvalues": [],
                "metrics": {"estimation": est.metrics}, "fit": _fit_info(r, outputs)}
               for r, est in zip(ident.fits, ident.estimation)]
        report["per_flight"] = per
        names = list(ident.model.free)
        vals = np.array([[p["parameters"][k]["value"] for k in names] for p in per])
        report["parameters"] = {
            k: {"value": float(vals[:, i].mean()), "std": float(vals[:, i].std(ddof=1)),
                "spread_over_flights": True}
            for i, k in enumerate(names)
        }
        report["summary"] = ("top-level parameters are the mean over the per-flight fits "
                             "(phase-aligned to the first flight); their std is the spread")
    if ident.validation:
        report["metrics"]["validation"] = pooled_metrics(ident.validation)
        report["validation_flights"] = [
            {"flight": v.name, "metrics": v.metrics,
             "phase_offset": v.local_params["phase_offset"]}
            for v in ident.validation
        ]
    if steady:
        report["steady_vs_manoeuvre"] = {
            s.flight: {"split_index": s.split, "frequency": s.frequency, **s.summary}
            for s in steady
        }
    return report


def combined_report(ident: CombinedIdentification) -> dict:
    """The `report.json` of `fwid identify --model combined` (CONTRACTS section 3).

    `parameters` holds both sub-models' parameters, `eigenvalues` those of the cycle-averaged
    part, `metrics` the full simulation's match per state and force. The sub-models' own
    reports are under `cycle_averaged` and `flapping`; `peaks` compares the first flapping
    peaks of every state and force, measured vs model.
    """
    from .report._json import identification_report
    from .validate._modes import modes

    eigs = ident.eigenvalues
    if ident.cycle is not None:
        cyc = identification_report(ident.cycle)
    else:  # a given cycle-averaged model: its values, no uncertainty
        m = ident.model
        cyc = {"model": m.name, "given": True, "modes": modes(eigs),
               "parameters": {k: {"value": float(m.params[k]), "std": None}
                              for k in m.free if k not in m.local and k in _cycle_names(m)}}
    flap = flapping_report(ident.flapping)
    report = {
        "model": "combined",
        "flights": list(ident.flights),
        "joint": bool(ident.flapping.joint),
        "parameters": {**cyc["parameters"], **flap["parameters"]},
        "eigenvalues": [[float(np.real(e)), float(np.imag(e))] for e in eigs],
        "modes": cyc.get("modes", []),
        "metrics": {"estimation": pooled_metrics(ident.estimation)},
        "phase_offsets": dict(ident.flapping.phase_offsets),
        "flapping_frequency": dict(ident.frequencies),
        "peaks": ident.peaks,
        "cycle_averaged": cyc,
        "flapping": flap,
        "units": "SI: rad, rad/s, m/s, N, N m; rms in the output's unit",
    }
    return add_validation(report, ident.validation)


def _cycle_names(model: GreyBoxModel) -> set[str]:
    outputs, harmonics = (model.f.outputs, model.f.harmonics)
    from .models._fourier import fourier_param_names

    return set(model.params) - set(fourier_param_names(outputs, harmonics))


def _peak_summary(peaks: dict) -> list[str]:
    out = [f"{'flight':<22}{'signal':<7}" + "".join(f"{f'peak {i + 1} meas/model':>24}"
                                                    for i in range(3))]
    for name, d in peaks.items():
        for k, v in d.items():
            cells = "".join(f"{a:>11.3e}/{b:<10.3e}  " for a, b in zip(v["measured"], v["model"]))
            out.append(f"{name[:21]:<22}{k:<7}{cells}")
    return out


def flapping_summary(report: dict) -> str:
    """The terminal summary of `fwid identify --model flap|combined`."""
    from .report._table import metrics_table, parameter_table

    out = [f"fwid identify: model {report['model']}, flights: {', '.join(report['flights'])}"]
    if "summary" in report:
        out.append(f"({report['summary']})")
    if report["model"] == "combined":
        from .report._table import modes_table

        out += ["", "cycle-averaged part (Section IV):",
                parameter_table(report["cycle_averaged"]["parameters"]), "",
                modes_table(report["cycle_averaged"]["modes"])]
        flap = report["flapping"]
    else:
        flap = report
    out += ["", f"flapping part, Eq. (12), {flap['harmonics']} harmonics (Table 7):",
            parameter_table(flap["parameters"])]
    out += ["", "flapping frequency [Hz] and phase offset [rad] per flight:"]
    for k, v in report["flapping_frequency"].items():
        out.append(f"  {k:<28}{v:8.3f}{report['phase_offsets'].get(k, 0.0):+9.3f}")
    title = ("flapping forces, match with estimation data (Table 8):"
             if report["model"] == "flap" else
             "combined model simulation, match with estimation data:")
    out += ["", metrics_table(flap["metrics"]["estimation"] if report["model"] == "flap"
                              else report["metrics"]["estimation"], title)]
    if "validation" in report["metrics"]:
        out += ["", metrics_table(report["metrics"]["validation"],
                                  "match with validation data (phase aligned):")]
    for name, s in report.get("steady_vs_manoeuvre", {}).items():
        out += ["", f"{name}: steady flight vs manoeuvre (Figures 14 vs 12):",
                f"{'output':<8}{'RMS steady':>12}{'% range':>9}{'non-harm %':>11}"
                f"{'RMS manoeuvre':>15}{'% range':>9}{'non-harm %':>11}"]
        for o in s["steady"]:
            a, b = s["steady"][o], s["manoeuvre"][o]
            out.append(f"{o:<8}{a['rms']:>12.3e}{a['rms_pct']:>9.2f}{a['nonharmonic_pct']:>11.2f}"
                       f"{b['rms']:>15.3e}{b['rms_pct']:>9.2f}{b['nonharmonic_pct']:>11.2f}")
    out += ["", "first flapping peaks, measured/model:"] + _peak_summary(report["peaks"])
    return "\n".join(out)


# -- the command line ------------------------------------------------------------------------


def _stem(name: str) -> str:
    return Path(name).stem


def identify_flapping(args, flights, validate) -> int:
    """`fwid identify --model flap|combined`: identify, print a summary, write the report and
    the figures (Figures 12-17) to `--out`. Returns the exit code."""
    from .report._figures import plot_poles
    from .report._json import write_json
    from .report._spectra import (
        plot_steady_vs_manoeuvre,
        plot_superposition,
        plot_time_and_spectrum,
    )

    t0 = time.perf_counter()
    progress = not getattr(args, "quiet", False)
    cutoff = float(getattr(args, "cutoff", 5.0))
    joint = bool(getattr(args, "joint", False))
    out = Path(args.out) if getattr(args, "out", None) else None
    figures = []  # (function, kwargs) drawn after the report is known to be complete

    if args.model == "flap":
        ident = identify_flapping_model(flights, validate=validate, joint=joint, cutoff=cutoff,
                                        progress=progress)
        steady = []
        for f in flights:
            try:
                steady.append(steady_vs_manoeuvre(f, ident.model.outputs, cutoff=cutoff))
            except InputError as e:
                _say(progress, f"steady vs manoeuvre skipped: {e}")
        report = flapping_report(ident, steady)
        for ff in ident.estimation:
            figures.append((plot_time_and_spectrum, ff, dict(
                f=ident.frequencies[ff.name], path=f"flap_fit_{_stem(ff.name)}.png",
                title=f"{ff.name}: flapping forces, estimation (Figure 12)")))
        for ff in ident.validation:
            figures.append((plot_time_and_spectrum, ff, dict(
                f=ident.frequencies[ff.name], path=f"flap_validation_{_stem(ff.name)}.png",
                title=f"{ff.name}: flapping forces, validation, phase aligned (Figure 13)")))
        for s in steady:
            figures.append((plot_steady_vs_manoeuvre, s.steady, dict(
                manoeuvre=s.manoeuvre, f=s.frequency,
                path=f"steady_vs_manoeuvre_{_stem(s.flight)}.png",
                title=f"{s.flight}: flapping model, steady flight vs manoeuvre (Figure 14)")))
    else:
        ident = identify_combined(flights, validate=validate, joint=joint, cutoff=cutoff,
                                  progress=progress)
        report = combined_report(ident)
        for ff in ident.flapping.estimation:
            figures.append((plot_time_and_spectrum, ff, dict(
                f=ident.frequencies[ff.name], path=f"flap_fit_{_stem(ff.name)}.png",
                title=f"{ff.name}: flapping forces, estimation (Figure 12)")))
        for ff in ident.estimation:
            p = ident.parts[ff.name]
            figures.append((plot_superposition, ff.t, dict(
                measured=ff.forces_measured, averaged=p["TA"], flapping=p["TV"],
                f=ident.frequencies[ff.name], path=f"superposition_{_stem(ff.name)}.png",
                title=f"{ff.name}: time-averaged + time-varying model (Figure 15)")))
            figures.append((plot_time_and_spectrum, ff, dict(
                f=ident.frequencies[ff.name], path=f"combined_fit_{_stem(ff.name)}.png",
                measured_label="Measured", model_label="Model",
                title=f"{ff.name}: combined model, estimation (Figure 16)")))
        for ff in ident.validation:
            figures.append((plot_time_and_spectrum, ff, dict(
                f=ident.frequencies[ff.name], path=f"combined_validation_{_stem(ff.name)}.png",
                measured_label="Measured", model_label="Model",
                title=f"{ff.name}: combined model, validation (Figure 17)")))
        eigs = [np.asarray(ident.eigenvalues)]
        figures.append((plot_poles, eigs, dict(
            labels=["cycle-averaged part"], path="poles.png",
            title="combined model: eigenvalues of the cycle-averaged part")))
    print(flapping_summary(report))
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        for fn, first, kw in figures:
            kw = dict(kw)
            kw["path"] = out / kw["path"]
            if fn is plot_poles:
                fn(first, kw.pop("labels"), **kw)
            elif fn is plot_superposition:
                fn(first, kw.pop("measured"), kw.pop("averaged"), kw.pop("flapping"), **kw)
            elif fn is plot_steady_vs_manoeuvre:
                fn(first, kw.pop("manoeuvre"), **kw)
            else:
                fn(first, **kw)
        write_json(out / "report.json", report)
        print(f"\nfwid: report and figures in {out}/ ({time.perf_counter() - t0:.1f} s)")
    return 0
