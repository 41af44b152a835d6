"""Split flight data into the cycle-averaged part and the flapping part (Section III.B, Figure 4).

The measurements are low-pass filtered at 40 Hz to remove noise (only the first three flapping
harmonics stand out from the noise), then split at 5 Hz, between the body modes (~1 Hz) and the
flapping frequency (~12 Hz): below is the cycle-averaged (time-averaged) part, used to identify the
cycle-averaged model (Section IV), above is the flapping (time-varying) part, used to identify the
Fourier-series model (Section V, Eq. 12). Both filters are zero-phase.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._errors import InputError
from ..data._flight import Flight
from ._filters import _concrete, check_cutoff, lowpass

# Columns carried through untouched: time, and the measured flapping frequency (an input of the
# flapping model, Section V.A, not a signal to be split).
SKIPPED = ("t", "f")
#: Butterworth order of the split between the cycle-averaged and the flapping part.
SPLIT_ORDER = 6


class Decomposition(eqx.Module):
    """The two parts of the (noise-filtered) flight data, by column (Section III.B, Figure 4).

    **Fields:**

    - `averaged`: the cycle-averaged part of each column (content below `split_cutoff`).
    - `flapping`: the flapping part of each column (between `split_cutoff` and `noise_cutoff`).
    - `noise_cutoff`: cut-off [Hz] of the noise low-pass, or `None` when no noise filter was applied
      (asked for, or the cut-off was at or above the Nyquist frequency).
    - `split_cutoff`: cut-off [Hz] between the two parts.
    - `noise_order`, `split_order`: Butterworth orders of the two zero-phase filters (static).

    `averaged[k] + flapping[k]` is the noise-filtered column `k` (to rounding), see `filtered`.
    """

    averaged: dict[str, Float[Array, "*batch n"]]
    flapping: dict[str, Float[Array, "*batch n"]]
    noise_cutoff: Float[Array, ""] | None
    split_cutoff: Float[Array, ""]
    noise_order: int = eqx.field(static=True, default=4)
    split_order: int = eqx.field(static=True, default=6)

    @property
    def names(self) -> tuple[str, ...]:
        """The decomposed columns, in order."""
        return tuple(self.averaged)

    @property
    def filtered(self) -> dict[str, Float[Array, "*batch n"]]:
        """The noise-filtered columns: cycle-averaged plus flapping part."""
        return {k: self.averaged[k] + self.flapping[k] for k in self.averaged}


def _noise_filter_applies(noise_cutoff, dt) -> bool:
    if noise_cutoff is None:
        return False
    fc, step = _concrete(noise_cutoff), _concrete(dt)
    if fc is None or step is None:
        return True
    return fc < 0.5 / step


def decompose(
    columns: Mapping[str, Float[ArrayLike, "*batch n"]],
    dt: float | Float[ArrayLike, ""],
    *,
    noise_cutoff: float | Float[ArrayLike, ""] | None = 40.0,
    split_cutoff: float | Float[ArrayLike, ""] = 5.0,
    noise_order: int = 4,
    split_order: int = SPLIT_ORDER,
    skip: Sequence[str] = SKIPPED,
    pad: str = "hybrid",
) -> Decomposition:
    """Split each column into its cycle-averaged and flapping parts (Section III.B).

    `filtered = lowpass(x, noise_cutoff)`, `averaged = lowpass(filtered, split_cutoff)`,
    `flapping = filtered - averaged`: both zero-phase Butterworth filters (see
    [`fwid.decomposition.lowpass`][]), so the two parts add back exactly to the filtered signal and
    neither lags. All columns are filtered together as one `(columns, ..., n)` array. Jit-able,
    vmap-able, and differentiable with respect to both cut-offs.

    **Arguments:**

    - `columns`: time histories by name, all of the same shape, time along the last axis.
    - `dt`: sample step [s].
    - `noise_cutoff`: cut-off [Hz] of the noise low-pass (paper: 40 Hz). `None` skips it; so does a
      (concrete) value at or above the Nyquist frequency, where the record holds nothing to remove.
    - `split_cutoff`: cut-off [Hz] between the cycle-averaged and the flapping part (paper: 5 Hz).
    - `noise_order`: Butterworth order of the noise filter (static, default 4). Note that a
      zero-phase filter halves the amplitude *at* its cut-off: with 40 Hz and order 4 a third
      harmonic at 37.5 Hz keeps about 63 % of its amplitude, at 39 Hz about 55 % (the paper's
      compromise between noise and flapping content); raise `noise_cutoff` or `noise_order` to
      keep more.
    - `split_order`: Butterworth order of the split (static, default 6: the zero-phase response
      falls 240 dB/decade, so a flapping line at 11 Hz leaks 8e-5 of its amplitude into the
      cycle-averaged part and body motion at 2 Hz leaks 2e-5 into the flapping part, while the
      step response rings by ~8 % (order 4: 1.8e-3, 7e-4 and ~7 %)).
    - `skip`: columns left out (default `t` and `f`: time, and the flapping frequency, an input).
    - `pad`: how the records are extended past their ends (static), see
      [`fwid.decomposition.lowpass`][]: the default `"hybrid"` continues the slow part by odd and the
      flapping part by even reflection, so neither part is thrown off at the ends by the other;
      `"odd"` reproduces `filtfilt` (and the paper's processing) more literally.

    **Returns:** a [`fwid.decomposition.Decomposition`][].

    **Raises:** `fwid.InputError` if the columns differ in shape, or a concrete cut-off is out of
    range (`split_cutoff` must lie below the Nyquist frequency and below `noise_cutoff`).
    """
    names = [k for k in columns if k not in skip]
    arrays = [jnp.asarray(columns[k]) for k in names]
    arrays = [a if jnp.issubdtype(a.dtype, jnp.floating) else a.astype(float) for a in arrays]
    shapes = {a.shape for a in arrays}
    if len(shapes) > 1:
        detail = ", ".join(f"{k} {a.shape}" for k, a in zip(names, arrays))
        raise InputError(f"decompose: the columns must all have the same shape, got {detail}")
    check_cutoff(split_cutoff, dt, "split cut-off")
    use_noise = _noise_filter_applies(noise_cutoff, dt)
    if use_noise:
        check_cutoff(noise_cutoff, dt, "noise cut-off")
        fn, fs = _concrete(noise_cutoff), _concrete(split_cutoff)
        if fn is not None and fs is not None and not fs < fn:
            raise InputError(f"split cut-off {fs:g} Hz must lie below the noise cut-off {fn:g} Hz")
    noise = jnp.asarray(noise_cutoff, dtype=float) if use_noise else None
    split = jnp.asarray(split_cutoff, dtype=float)
    if not names:
        return Decomposition({}, {}, noise, split, noise_order, split_order)
    stacked = jnp.stack(arrays)
    if use_noise:
        filtered = lowpass(stacked, dt, noise, order=noise_order, pad=pad)
    else:
        filtered = stacked
    averaged = lowpass(filtered, dt, split, order=split_order, pad=pad)
    flapping = filtered - averaged
    return Decomposition(
        averaged=dict(zip(names, averaged)),
        flapping=dict(zip(names, flapping)),
        noise_cutoff=noise,
        split_cutoff=split,
        noise_order=noise_order,
        split_order=split_order,
    )


def _flight_dt(flight: Flight):
    if isinstance(flight.t, jax.core.Tracer):
        return flight.t[1] - flight.t[0]
    return flight.dt


def _decompose_flight(flight, cutoff, noise_cutoff, order, noise_order, pad) -> Decomposition:
    if flight.t.shape[-1] < 2:
        raise InputError(f"{flight.name}: needs at least two samples to filter")
    return decompose(
        flight.columns,
        _flight_dt(flight),
        noise_cutoff=noise_cutoff,
        split_cutoff=cutoff,
        noise_order=noise_order,
        split_order=order,
        pad=pad,
    )


def cycle_averaged(
    flight: Flight,
    *,
    cutoff: float | Float[ArrayLike, ""] = 5.0,
    noise_cutoff: float | Float[ArrayLike, ""] | None = 40.0,
    order: int = 6,
    noise_order: int = 4,
    pad: str = "hybrid",
) -> Flight:
    """The flight with every column replaced by its cycle-averaged part (Sections III.B, IV.A).

    Used before fitting the cycle-averaged model: the states, the forces *and the control
    deflections* are cycle-averaged, so the elevator's ripple at the flapping frequency does not
    enter the model through the input (Section IV.A). `t`, the flapping frequency `f`, the trim
    and the other fields are kept.

    **Arguments:** `flight`, and `cutoff` (the split, 5 Hz), `noise_cutoff`, `order`,
    `noise_order`, `pad` as `split_cutoff`, `noise_cutoff`, `split_order`, `noise_order`, `pad` of
    [`fwid.decomposition.decompose`][].

    **Returns:** a new `Flight`.
    """
    parts = _decompose_flight(flight, cutoff, noise_cutoff, order, noise_order, pad)
    return flight.with_columns(**parts.averaged)


def flapping_part(
    flight: Flight,
    *,
    cutoff: float | Float[ArrayLike, ""] = 5.0,
    noise_cutoff: float | Float[ArrayLike, ""] | None = 40.0,
    order: int = 6,
    noise_order: int = 4,
    pad: str = "hybrid",
) -> Flight:
    """The flight with every column replaced by its flapping part (Sections III.B, V.A).

    The data the Fourier-series model (Eq. 12) is fitted to. The flapping part oscillates about
    zero, so the trim value `<col>0` of every replaced column is set to zero (its perturbation is
    itself); `t`, `f` (the model's input) and the other fields are kept.

    **Arguments:** as [`fwid.decomposition.cycle_averaged`][].

    **Returns:** a new `Flight`.
    """
    parts = _decompose_flight(flight, cutoff, noise_cutoff, order, noise_order, pad)
    out = flight.with_columns(**parts.flapping)
    trim = dict(flight.trim)
    for k in parts.names:
        if k + "0" in trim:
            trim[k + "0"] = jnp.zeros_like(trim[k + "0"])
    return eqx.tree_at(lambda fl: fl.trim, out, trim)


def edge_samples(n: int, dt: float, edge: float = 0.2) -> int:
    """How many samples to drop at each end of an `n`-sample record split by the zero-phase
    filters (Sec. III.B): `edge` seconds, where the filter sees past the record's ends; none
    when fewer than 50 samples would remain."""
    k = int(round(edge / dt))
    return k if n - 2 * k >= 50 else 0
