"""What the diagnosis sees of a flight: cycle-averaged perturbations, flapping phase, loads."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence

import numpy as np

from .._errors import DiagnosisWarning, ExcitationError, InputError
from ..data import Flight
from ..decomposition import SPLIT_ORDER, decompose, flapping_phase, lowpass
from ..models import fourier_regressors

#: Loads of each axis and the cycle-averaged signals their linear model uses (Eqs. 2-6).
AXIS_LOADS = {"lon": ("X", "Z", "M"), "lat": ("Y", "L", "N")}
AXIS_STATES = {"lon": ("u", "w", "q"), "lat": ("v", "p", "r")}
AXIS_INPUT = {"lon": "de", "lat": "dr"}
#: Signals that must exist for an axis to be diagnosed.
REQUIRED = {
    "lon": ("u", "w", "q", "theta", "de", "f", "X", "Z", "M"),
    "lat": ("v", "p", "r", "phi", "dr", "f", "Y", "L", "N"),
}
#: Seconds dropped at each end (edge effects of the zero-phase filters).
EDGE = 0.2


def other(axis: str) -> str:
    return "lat" if axis == "lon" else "lon"


@dataclasses.dataclass(frozen=True)
class Signals:
    """One flight (or one block of a flight) prepared for the diagnosis.

    - `slow`: cycle-averaged perturbations (below the 5 Hz split, Section III.B) of every
      state and input present, by name; `fast`: their parts above the split.
    - `loads`: the measured loads split as in Section III.B, `loads[band][load]` with `band`
      one of `BANDS`: `"averaged"` (below the split) and `"flapping"` (the harmonics).
    - `phase`: the flapping phase `int 2 pi f dt` (drives Eq. 12).
    - `manoeuvre`: True from the first input on.
    - `cutoff`: the split [Hz] (`averaged` splits another signal as the loads were).
    - `whole`, `edge`: the controls as commanded (`commanded`) over the whole flight,
      before the `edge` samples at each end were dropped (`over_whole`); `None` for a block.
    """

    name: str
    t: np.ndarray
    dt: float
    phase: np.ndarray
    f_mean: float
    f_spread: float
    slow: dict[str, np.ndarray]
    fast: dict[str, np.ndarray]
    loads: dict[str, dict[str, np.ndarray]]
    manoeuvre: np.ndarray
    cutoff: float = 5.0
    whole: dict[str, np.ndarray] | None = None
    edge: int = 0

    @property
    def n(self) -> int:
        return len(self.t)

    def block_rows(self, i: int, count: int) -> tuple[int, int]:
        """First and one-past-last sample of block `i` of `count` contiguous blocks."""
        edges = np.linspace(0, self.n, count + 1).astype(int)
        return int(edges[i]), int(edges[i + 1])

    def block(self, i: int, count: int) -> Signals:
        """Block `i` of `count` contiguous blocks (a scoring unit)."""
        s = slice(*self.block_rows(i, count))
        return Signals(
            name=f"{self.name}[{i + 1}/{count}]",
            t=self.t[s],
            dt=self.dt,
            phase=self.phase[s],
            f_mean=self.f_mean,
            f_spread=self.f_spread,
            slow={k: v[s] for k, v in self.slow.items()},
            fast={k: v[s] for k, v in self.fast.items()},
            loads={b: {k: v[s] for k, v in d.items()} for b, d in self.loads.items()},
            manoeuvre=self.manoeuvre[s],
            cutoff=self.cutoff,
        )

    def measured(self, name: str) -> np.ndarray:
        """The perturbation `name` below the noise filter, both parts together (`slow` plus
        `fast`; zeros when the flight lacks it): the signal as measured, before the split."""
        zero = np.zeros(self.n)
        return self.slow.get(name, zero) + self.fast.get(name, zero)

    def commanded(self, name: str) -> np.ndarray:
        """The control `name` as commanded: as measured (`measured`) less its flapping
        ripple (`commanded`)."""
        return commanded(self.measured(name), self.phase)

    def over_whole(self, name: str, fn) -> np.ndarray:
        """`fn(control)`, `fn` a filter of the control `name` as commanded (a servo, then
        the split), computed over the whole flight, then cut to this flight's samples as
        they were: the same edges as the loads, where filtering the cut signal would not be.
        Without the whole record (`whole` None: a block, or signals made by hand) the
        samples held are used."""
        if self.whole is None:
            return fn(self.commanded(name))
        whole = self.whole.get(name, np.zeros(self.n + 2 * self.edge))
        return fn(whole)[self.edge:self.edge + self.n]


#: Harmonics of the flapping phase in a control surface's ripple (`commanded`).
RIPPLE_HARMONICS = 3


def commanded(x: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """A control surface's deflection `x` less its flapping ripple: the least-squares fit of
    `RIPPLE_HARMONICS` harmonics of the flapping phase `phase` (Eq. 12's regressors, constant
    amplitudes) removed. The ripple is the flapping wings' pull on the surface and its
    linkage, locked to the wing beat, not what the servo was asked for (Section IV.A: the
    deflections are cycle-averaged), so a servo (`actuator-dynamics`) acts on the rest; a
    rate limit or a backlash fed the ripple as well would bind on every wing beat. Steps and
    manoeuvres, not locked to the phase, keep their edges (a low-pass would smooth them)."""
    x = np.asarray(x, dtype=float)
    A = fourier_regressors(phase, RIPPLE_HARMONICS)
    A -= A.mean(axis=0)
    coef, *_ = np.linalg.lstsq(A, x - x.mean(), rcond=None)
    return x - A @ coef


def averaged(x: np.ndarray, dt: float, cutoff: float) -> np.ndarray:
    """The cycle-averaged part of `x` by the split's own low-pass (Section III.B,
    `fwid.decomposition.decompose`): what the loads' averaged part holds of a load that `x`
    drives, for a signal made from the measured ones (a servo's output) rather than
    measured itself."""
    return np.asarray(lowpass(np.asarray(x, float), dt, cutoff, order=SPLIT_ORDER))


SLOW = ("u", "w", "q", "theta", "v", "p", "r", "phi", "de", "dr", "f")
LOADS = ("X", "Y", "Z", "L", "M", "N")
#: The two parts of the loads (Section III.B).
BANDS = ("averaged", "flapping")


def signals(flight: Flight, *, cutoff: float = 5.0) -> Signals:
    """Prepare `flight` for the diagnosis (see `Signals`); `EDGE` s are dropped at each end."""
    dt = flight.dt
    names = [c for c in SLOW + LOADS if c in flight and c != "f"]
    parts = decompose({c: flight[c] for c in names}, dt, split_cutoff=cutoff)
    keep = slice(round(EDGE / dt), flight.n - round(EDGE / dt))
    f = np.asarray(flight["f"], dtype=float)
    phase = _phase(flight)
    slow = {c: np.asarray(parts.averaged[c] - flight.trim_value(c))[keep]
            for c in SLOW if c in names}
    slow["f"] = f[keep] - np.mean(f)
    fast = {c: np.asarray(parts.flapping[c])[keep] for c in SLOW if c in names}
    loads = {
        "averaged": {c: np.asarray(parts.averaged[c])[keep] for c in LOADS if c in names},
        "flapping": {c: np.asarray(parts.flapping[c])[keep] for c in LOADS if c in names},
    }
    t = np.asarray(flight.t)[keep]
    manoeuvre = np.arange(flight.n)[keep] >= flight.first_input
    return Signals(
        name=flight.name,
        t=t,
        dt=dt,
        phase=phase[keep],
        f_mean=float(np.mean(f)),
        f_spread=float(np.ptp(f)),
        slow=slow,
        fast=fast,
        loads=loads,
        manoeuvre=manoeuvre,
        cutoff=cutoff,
        whole={c: commanded(_both(parts, flight, c), phase) for c in AXIS_INPUT.values()
               if c in names},
        edge=keep.start,
    )


def _phase(flight: Flight) -> np.ndarray:
    """The whole flight's flapping phase from its measured frequency `f`."""
    return np.asarray(flapping_phase(np.asarray(flight["f"], dtype=float), flight.dt))


def _both(parts, flight: Flight, name: str) -> np.ndarray:
    """Both parts of `name` in the decomposition `parts` of `flight`, less its trim."""
    return np.asarray(parts.averaged[name] + parts.flapping[name]) - flight.trim_value(name)


def command(flight: Flight, name: str, cutoff: float = 5.0) -> np.ndarray:
    """The whole flight's control `name` as commanded (`commanded`: below the noise filter,
    both parts of the split less the flapping ripple), as `Signals.whole` holds it."""
    both = _both(decompose({name: flight[name]}, flight.dt, split_cutoff=cutoff), flight, name)
    return commanded(both, _phase(flight))


def cycle_averaged(flight: Flight, names: Sequence[str], cutoff: float = 5.0
                   ) -> dict[str, np.ndarray]:
    """The whole flight's cycle-averaged perturbations (below the split, less the trim) of
    those of `names` it has, as `Signals.slow` holds them without the edges dropped."""
    have = [c for c in names if c in flight]
    parts = decompose({c: flight[c] for c in have}, flight.dt, split_cutoff=cutoff)
    return {c: np.asarray(parts.averaged[c] - flight.trim_value(c)) for c in have}


def check_axis(flights: Sequence[Flight], axis: str, role: str) -> None:
    """Every flight has what the diagnosis of `axis` needs; else an `InputError` naming the
    flight and the missing columns (`Flight.require`)."""
    if axis not in REQUIRED:
        raise InputError(f"axis must be 'lon' or 'lat', got {axis!r}")
    if not flights:
        raise InputError(f"no {role} flights given")
    for fl in flights:
        fl.require(REQUIRED[axis])


def check_excitation(sigs, axis: str) -> None:
    """Raise `ExcitationError` when the training flights `sigs` hardly move the control of
    `axis`; warn (`DiagnosisWarning`) when they look like manoeuvres of the other axis."""
    d = AXIS_INPUT[axis]
    moves = [np.ptp(s.slow[d]) for s in sigs]
    if max(moves) < 1e-3:  # rad: a twentieth of a degree
        raise ExcitationError(
            f"too little excitation to diagnose the {axis} axis: '{d}' moves by at most "
            f"{max(moves):.2g} rad in the training flights ({', '.join(s.name for s in sigs)}); "
            "use flights with a manoeuvre (a 3211 or doublet on the control)"
        )
    o = AXIS_INPUT[other(axis)]
    if all(o in s.slow for s in sigs):
        theirs = np.median([np.std(s.slow[o]) for s in sigs])
        ours = np.median([np.std(s.slow[d]) for s in sigs])
        if theirs > 3.0 * ours:
            warnings.warn(
                f"the training flights look like {other(axis)} manoeuvres: '{o}' moves "
                f"{theirs / max(ours, 1e-12):.0f} times more than '{d}' (median standard "
                f"deviation), but the {axis} axis is diagnosed; pass axis='{other(axis)}' "
                f"(CLI: --axis {other(axis)}) to diagnose the manoeuvre flown",
                DiagnosisWarning, stacklevel=3)
