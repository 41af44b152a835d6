"""Steady flight vs manoeuvre (Section V.B, Figures 12 and 14): the flapping model fitted to a
flight's quiet start and to its manoeuvre, and how much of the flapping is not periodic."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._errors import InputError
from ..data._flight import Flight
from ..estimate._problem import FitResult
from ..models._fourier import fourier_model
from ..validate._harmonics import nonharmonic_share
from ._flapping import fit_fourier, fourier_flight_fit
from ._flapping_data import display_inputs, flapping_data, fourier_experiment, outputs_for, trimmed
from ._flight_fit import FlightFit


@dataclass(frozen=True, repr=False)
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

    def __repr__(self) -> str:
        share = {part: {o: round(v["nonharmonic_pct"], 1) for o, v in d.items()}
                 for part, d in self.summary.items()}
        return (f"SteadyVsManoeuvre({self.flight!r}, split at sample {self.split}, "
                f"f={self.frequency:.2f} Hz, non-harmonic share %: {share})")



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
    outputs = outputs_for([flight], outputs)
    split = flight.first_input if split is None else int(split)
    t, ph, z = flapping_data(flight, outputs, cutoff=cutoff, noise_cutoff=noise_cutoff)
    sl_all = trimmed(flight, t)
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
    full_inputs = display_inputs(flight, outputs, cutoff, fourier_experiment(t, ph, z), sl_all)
    parts, fits, summary = [], [], {}
    fmax = min((harmonics + 0.5) * float(np.max(np.asarray(flight["f"]))), 0.5 / flight.dt)
    if noise_cutoff is not None:
        fmax = min(fmax, noise_cutoff)
    for label, sl in (("steady", slice(0, k)), ("manoeuvre", slice(k, None))):
        e = fourier_experiment(t[sl], ph[sl], z[sl])
        r = fit_fourier(model, [e], [f"{flight.name}[{label}]"], progress)
        inputs = {kk: v[sl] for kk, v in full_inputs.items()}
        ff = fourier_flight_fit(f"{flight.name} ({label})", t[sl], inputs, r.model, e)
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
