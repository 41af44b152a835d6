"""The flapping part of a flight as Eq. (12) sees it: the flapping forces, the flapping phase
(the integral of the measured `2 pi f`) and the cycle-averaged control input; shared by the
flapping, steady-vs-manoeuvre and combined pipelines (Sections V-VI)."""

from __future__ import annotations

from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from .._errors import FlightDataError
from ..data._flight import Flight
from ..data._trim import input_column
from ..decomposition._filters import lowpass
from ..decomposition._frequency import check_flapping_frequency, flapping_phase
from ..decomposition._split import edge_samples, flapping_part
from ..models._fourier import LAT_OUTPUTS, LON_OUTPUTS
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment, experiment


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


def outputs_for(flights: Sequence[Flight], outputs) -> tuple[str, ...]:
    if outputs is not None:
        return tuple(outputs)
    return LAT_OUTPUTS if flight_axis(flights[0]) == "lat" else LON_OUTPUTS


def input_name(outputs) -> str:
    return "dr" if tuple(outputs) == LAT_OUTPUTS else "de"


def phase_of(flight: Flight) -> np.ndarray:
    return np.asarray(flapping_phase(flight["f"], flight.dt))


def check_frequency_of(flight: Flight, z: np.ndarray, outputs, sl: slice) -> str:
    """Cross-check the `f` column against the flapping forces; fine if any output agrees."""
    first = None
    f = np.asarray(flight["f"])[sl]
    for j in range(z.shape[1]):
        try:
            return check_flapping_frequency(f, z[:, j], flight.dt, name=flight.name)
        except FlightDataError as e:
            first = first or e
    raise first


def slow(flight: Flight, col: str, cutoff: float) -> np.ndarray:
    """The cycle-averaged perturbation of one column (the input as the models see it)."""
    return np.asarray(lowpass(flight.perturbation(col), flight.dt, cutoff, order=6))


def _cycle_forces(cycle: GreyBoxModel, flight: Flight, cutoff: float) -> np.ndarray:
    """`F_TA` of Eqs. (13)-(15) on the measured states: what the cycle-averaged model already
    explains of the forces, including the part driven by the flapping in the states."""
    flight.require(cycle.states)
    xs = jnp.stack([flight.perturbation(c) for c in cycle.states], axis=-1)
    us = jnp.stack([jnp.asarray(slow(flight, c, cutoff)) for c in cycle.inputs], axis=-1)
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
    k = edge_samples(flight.n, flight.dt, edge)
    sl = slice(k, flight.n - k)
    return np.asarray(flight.t)[sl], phase_of(flight)[sl], z[sl]


def trimmed(flight: Flight, t: np.ndarray) -> slice:
    """The samples of `flight` that `flapping_data` kept (`t` its time)."""
    k = (flight.n - t.shape[0]) // 2
    return slice(k, k + t.shape[0])


def fourier_experiment(t, phase, z) -> Experiment:
    return Experiment(t, np.asarray(phase)[:, None], z, x0=np.zeros(0))


def display_inputs(flight, outputs, cutoff, exp, sl: slice) -> dict:
    """The cycle-averaged control input (for the paper's scaled input) and the phase."""
    out = {}
    col = input_name(outputs)
    if col in flight:
        out[col] = slow(flight, col, cutoff)[sl]
    out["phase"] = np.asarray(exp.u[:, 0])
    return out
