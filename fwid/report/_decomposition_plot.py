"""Figure of the cycle-averaged / flapping decomposition, like the paper's Figure 4."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np
from jaxtyping import ArrayLike, Float
from matplotlib.figure import Figure

from .._errors import InputError

_COLOURS = {"raw": "0.75", "filtered": "0.2", "averaged": "tab:blue", "flapping": "tab:red"}


def _amplitude_spectrum(x: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum (Hann window, amplitude-corrected), without f = 0."""
    window = np.hanning(x.size)
    amp = 2.0 * np.abs(np.fft.rfft((x - x.mean()) * window)) / window.sum()
    freqs = np.fft.rfftfreq(x.size, dt)
    return freqs[1:], amp[1:]


def _as_1d(value, what: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 1:
        raise InputError(
            f"plot_decomposition: {what} must be one time history, got shape {arr.shape}"
        )
    return arr


def plot_decomposition(
    t: Float[ArrayLike, " n"],
    raw: Mapping[str, Float[ArrayLike, " n"]] | None,
    decomposition,
    names: Sequence[str],
    *,
    path: str | os.PathLike | None = None,
) -> Figure:
    """Plot the decomposition of some signals into cycle-averaged and flapping parts (Figure 4).

    One row per signal, three panels: (1) the measurement, noise-filtered, with its cycle-averaged
    part over it (and the unfiltered measurement in grey when `raw` is given); (2) the flapping
    part; (3) the amplitude spectra on a logarithmic frequency axis, the flapping band above the
    split cut-off shaded and the noise cut-off dashed (Figure 4b).

    Built with the object-oriented API (`matplotlib.figure.Figure`), so it touches no global pyplot
    state and works with any backend.

    **Arguments:**

    - `t`: time [s], uniformly sampled.
    - `raw`: the measurements before filtering, by name (a dict or a `fwid.data.Flight`), or
      `None`.
    - `decomposition`: a [`fwid.decomposition.Decomposition`][] of the same samples.
    - `names`: the signals to plot, e.g. `("X", "Y", "Z")`.
    - `path`: if given, the figure is also written there (format from the suffix, e.g. `.png`).

    **Returns:** the `matplotlib.figure.Figure` (axes in row-major order, three per signal).
    """
    names = list(names)
    if not names:
        raise InputError("plot_decomposition: no signal names given")
    missing = [k for k in names if k not in decomposition.averaged]
    if missing:
        raise InputError(
            f"plot_decomposition: {', '.join(map(repr, missing))} not in the decomposition "
            f"(has: {', '.join(decomposition.names)})"
        )
    t = _as_1d(t, "t")
    if t.size < 2:
        raise InputError("plot_decomposition: needs at least two samples")
    dt = float(t[1] - t[0])
    split = float(decomposition.split_cutoff)
    noise = None if decomposition.noise_cutoff is None else float(decomposition.noise_cutoff)
    nyquist = 0.5 / dt

    fig = Figure(figsize=(13.0, 2.6 * len(names) + 0.6), layout="constrained")
    axes = fig.subplots(len(names), 3, squeeze=False, gridspec_kw={"width_ratios": [3, 3, 2]})
    for row, name in enumerate(names):
        averaged = _as_1d(decomposition.averaged[name], f"the cycle-averaged part of {name!r}")
        flapping = _as_1d(decomposition.flapping[name], f"the flapping part of {name!r}")
        filtered = averaged + flapping
        if filtered.size != t.size:
            raise InputError(
                f"plot_decomposition: {name!r} has {filtered.size} samples, t has {t.size}"
            )
        measured = None if raw is None else _as_1d(raw[name], f"raw {name!r}")
        ax_time, ax_flap, ax_spec = axes[row]

        if measured is not None:
            ax_time.plot(t, measured, color=_COLOURS["raw"], lw=0.6, label="measured")
        ax_time.plot(t, filtered, color=_COLOURS["filtered"], lw=0.8, label="filtered")
        ax_time.plot(t, averaged, color=_COLOURS["averaged"], lw=1.6, label="cycle-averaged")
        ax_time.set_ylabel(name)
        ax_flap.plot(t, flapping, color=_COLOURS["flapping"], lw=0.8, label="flapping")
        ax_flap.axhline(0.0, color="0.5", lw=0.5)

        band = f"flapping band (> {split:g} Hz)"
        ax_spec.axvspan(split, nyquist, color="0.9", zorder=0, label=band)
        if noise is not None:
            label = f"noise cut-off {noise:g} Hz"
            ax_spec.axvline(noise, color="0.4", ls="--", lw=0.8, label=label)
        spectra = [("filtered", filtered), ("averaged", averaged), ("flapping", flapping)]
        if measured is not None:
            spectra.insert(0, ("raw", measured))
        for key, signal in spectra:
            freqs, amp = _amplitude_spectrum(signal, dt)
            ax_spec.plot(freqs, amp, color=_COLOURS[key], lw=0.9 if key != "averaged" else 1.3)
        ax_spec.set_xscale("log")
        ax_spec.set_xlim(1.0 / (t.size * dt), nyquist)
        ax_spec.set_ylabel(f"|{name}|")

        for ax in (ax_time, ax_flap):
            ax.set_xlim(t[0], t[-1])
        if row == 0:
            ax_time.set_title("Filtered measurement and cycle-averaged part")
            ax_flap.set_title("Flapping part")
            ax_spec.set_title("Amplitude spectrum")
            ax_time.legend(loc="upper right", fontsize="small")
            ax_spec.legend(loc="upper right", fontsize="small")
        if row == len(names) - 1:
            ax_time.set_xlabel("t [s]")
            ax_flap.set_xlabel("t [s]")
            ax_spec.set_xlabel("f [Hz]")

    if path is not None:
        fig.savefig(os.fspath(path), dpi=110)
    return fig
