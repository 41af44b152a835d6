"""Amplitude spectra and the flapping peaks: measured vs model in time and frequency
(Figures 12-17).

Object-oriented matplotlib only (no pyplot state).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from jaxtyping import ArrayLike, Float
from matplotlib.figure import Figure

from ..validate._harmonics import harmonic_amplitudes as harmonic_amplitudes
from ._figures import _scaled_input

_DEG = {"q", "p", "r", "theta", "phi", "psi", "alpha", "de", "dr"}
_UNITS = {"q": "deg/s", "p": "deg/s", "r": "deg/s", "theta": "deg", "phi": "deg",
          "u": "m/s", "w": "m/s", "v": "m/s", "X": "N", "Y": "N", "Z": "N",
          "L": "N m", "M": "N m", "N": "N m"}


def _display(name, x):
    return np.rad2deg(x) if name in _DEG else np.asarray(x)


def amplitude_spectrum(
    x: Float[ArrayLike, "*channels n"], dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum along the last axis, as the paper's `|X|`, `|Z|`, `|M|`.

    The mean is removed and the record tapered with a Hann window; the result is scaled so
    that a steady sinusoid of amplitude `A` shows a peak of height `A` (at a bin centre).

    **Returns:** `(freqs, amplitude)`, the frequencies [Hz] without `f = 0`, and the amplitudes
    in the signal's unit, shape `(*channels, n_freqs)`.
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    window = np.hanning(n)
    xc = x - x.mean(axis=-1, keepdims=True)
    amp = 2.0 * np.abs(np.fft.rfft(xc * window, axis=-1)) / window.sum()
    freqs = np.fft.rfftfreq(n, dt)
    return freqs[1:], amp[..., 1:]


def _unit(k):
    return _UNITS.get(k, "")


def _log_ticks(ax, lo, hi):
    """Plain-number ticks on a logarithmic frequency axis (5, 10, 20, 50, ... Hz)."""
    from matplotlib.ticker import FixedLocator, NullFormatter, ScalarFormatter

    ticks = [v for v in (1, 2, 5, 10, 20, 30, 50, 100, 200) if lo <= v <= hi]
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())


def _spectrum_axes(ax, freqs, series, f_flap, harmonics, fmax, unit):
    for (label, amp, style) in series:
        ax.plot(freqs, amp, label=label, **style)
    ax.set_xscale("log")
    lo = 0.4 * f_flap if f_flap else freqs[0]
    ax.set_xlim(lo, fmax)
    _log_ticks(ax, lo, fmax)
    if f_flap:
        for k in range(1, harmonics + 1):
            if k * f_flap < fmax:
                ax.axvline(k * f_flap, color="0.6", lw=0.6, ls=":")
    sel = (freqs >= lo) & (freqs <= fmax)
    top = max((np.max(a[sel]) for _, a, _ in series if np.any(sel)), default=1.0)
    ax.set_ylim(0, 1.1 * top if top > 0 else 1.0)


def zoom_window(t: np.ndarray, f: float | None, cycles: int) -> tuple[float, float]:
    """`cycles` flapping cycles (of `f` Hz) in the middle of the record `t` [s]; without `f`,
    a tenth of the record."""
    t0, t1 = float(t[0]), float(t[-1])
    width = min(cycles / f if f else 0.1 * (t1 - t0), t1 - t0)
    mid = 0.5 * (t0 + t1)
    return mid - 0.5 * width, mid + 0.5 * width


def plot_time_and_spectrum(
    flight_fit,
    *,
    f: float | None = None,
    harmonics: int = 3,
    fmax: float | None = None,
    zoom_cycles: int = 4,
    path: str | Path | None = None,
    title: str = "",
    measured_label: str = "Reconstructed",
    model_label: str = "Estimated",
) -> Figure:
    """Measured vs model in the time domain and as amplitude spectra (Figures 12-14, 16, 17).

    One row per signal of the [`fwid.FlightFit`][] (its outputs, then its forces, if any):
    left the whole time history with the scaled input (the paper's "scaled elev. input"),
    the zoomed span shaded; middle a zoom on `zoom_cycles` flapping cycles in the middle of
    the record, where the model's waveform can be read against the data (the RMS error in its
    title); right the amplitude spectra, in the signal's unit, on a logarithmic frequency
    axis with the flapping harmonics dotted.

    **Arguments:**
    - `flight_fit`: a [`fwid.FlightFit`][] (its first input is drawn scaled).
    - `f`: the (mean) flapping frequency [Hz], for the harmonic marks, the zoom and the axis
      range.
    - `harmonics`: how many harmonics to mark.
    - `fmax`: the top of the frequency axis (default: Nyquist, at most 60 Hz).
    - `zoom_cycles`: flapping cycles in the zoom (without `f`: a tenth of the record).
    - `path`: where to save the figure (format from the suffix).
    - `title`, `measured_label`, `model_label`: labels.

    **Returns:** the `matplotlib.figure.Figure`.
    """
    t = np.asarray(flight_fit.t)
    dt = float(t[1] - t[0])
    signals = [(k, flight_fit.measured[k], flight_fit.simulated[k]) for k in flight_fit.measured]
    signals += [(k, flight_fit.forces_measured[k], flight_fit.forces_simulated[k])
                for k in flight_fit.forces_measured]
    nrow = len(signals)
    fig = Figure(figsize=(14, 1.9 * nrow + 0.7), layout="constrained")
    axes = fig.subplots(nrow, 3, squeeze=False, gridspec_kw=dict(width_ratios=(1.6, 0.9, 1)))
    fmax = min(60.0, 0.5 / dt) if fmax is None else fmax
    inputs = {k: v for k, v in flight_fit.inputs.items() if k != "phase"}
    u_name, u = next(iter(inputs.items())) if inputs else (None, None)
    lo, hi = zoom_window(t, f, zoom_cycles)
    span = (t >= lo) & (t <= hi)
    for row, (k, zm, ys) in enumerate(signals):
        zm, ys = _display(k, zm), _display(k, ys)
        unit = _unit(k)
        label = f"{k} [{unit}]" if unit else k
        ax, zoom = axes[row, 0], axes[row, 1]
        for a, sel in ((ax, slice(None)), (zoom, span)):
            a.plot(t[sel], zm[sel], color="0.2", lw=0.9, label=measured_label)
            a.plot(t[sel], ys[sel], color="C3", lw=1.0, ls="--", label=model_label)
        if u is not None and np.ptp(u) > 0:
            ax.plot(t, _scaled_input(np.asarray(u), zm), color="C0", lw=0.8, alpha=0.6,
                    label=f"Scaled {u_name} input")
        ax.axvspan(lo, hi, color="C1", alpha=0.12, lw=0)
        ax.set_ylabel(label)
        zoom.set_xlim(lo, hi)
        m = flight_fit.metrics.get(k)
        if m:
            rms = float(_display(k, m["rms"]))
            zoom.set_title(f"RMS {rms:.3g} {unit} ({m['rms_pct']:.1f} % of range)", fontsize=7)
        freqs, amp = amplitude_spectrum(np.stack([zm, ys]), dt)
        _spectrum_axes(axes[row, 2], freqs,
                       [(measured_label, amp[0], dict(color="0.2", lw=0.9)),
                        (model_label, amp[1], dict(color="C3", lw=1.0, ls="--"))],
                       f, harmonics, fmax, unit)
        axes[row, 2].set_ylabel(f"|{k}| [{unit}]" if unit else f"|{k}|")
    axes[0, 0].legend(fontsize=7, loc="lower left", bbox_to_anchor=(0, 1), ncol=3,
                      frameon=False)  # above the panel, off the traces
    axes[0, 2].legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("t [s]")
    cycles = f" ({zoom_cycles} flapping cycles)" if f else ""
    axes[-1, 1].set_xlabel(f"t [s], zoom{cycles}")
    axes[-1, 2].set_xlabel("f [Hz]")
    fig.suptitle(title or flight_fit.name)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_superposition(
    t: Float[ArrayLike, " n"],
    measured: Mapping[str, Float[ArrayLike, " n"]],
    averaged: Mapping[str, Float[ArrayLike, " n"]],
    flapping: Mapping[str, Float[ArrayLike, " n"]],
    *,
    f: float | None = None,
    harmonics: int = 3,
    path: str | Path | None = None,
    title: str = "",
) -> Figure:
    """The linear addition of the two sub-models in the frequency domain (Figure 15).

    For each force: the measured amplitude spectrum, that of the time-averaged (TA) model,
    that of the time-varying (TV) model, and that of their sum, on a log-log scale.

    **Arguments:** `t` time [s]; `measured`, `averaged`, `flapping`: the measured forces and
    the two model terms by name; `f` the flapping frequency for the harmonic marks; `path`.

    **Returns:** the `matplotlib.figure.Figure`.
    """
    t = np.asarray(t)
    dt = float(t[1] - t[0])
    names = list(measured)
    fig = Figure(figsize=(6.5, 2.1 * len(names) + 0.6), layout="constrained")
    axes = fig.subplots(len(names), 1, squeeze=False)[:, 0]
    for ax, k in zip(axes, names):
        ta, tv = np.asarray(averaged[k]), np.asarray(flapping[k])
        freqs, amp = amplitude_spectrum(
            np.stack([np.asarray(measured[k]), ta, tv, ta + tv]), dt)
        ax.loglog(freqs, amp[0], color="0.2", lw=0.9, label="Measured")
        ax.loglog(freqs, amp[1], color="C0", lw=1.0, label="TA model")
        ax.loglog(freqs, amp[2], color="C1", lw=1.0, label="TV model")
        ax.loglog(freqs, amp[3], color="C3", lw=1.0, ls="--", label="TA + TV")
        if f:
            for n in range(1, harmonics + 1):
                ax.axvline(n * f, color="0.6", lw=0.6, ls=":")
        top = amp.max()
        ax.set_ylim(top * 1e-5, top * 2)
        ax.set_ylabel(f"|{k}| [{_unit(k)}]")
    axes[0].legend(fontsize=7, ncol=4, loc="lower left")
    axes[-1].set_xlabel("f [Hz]")
    fig.suptitle(title or "Time-averaged + time-varying model (Figure 15)")
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_steady_vs_manoeuvre(
    steady,
    manoeuvre,
    *,
    f: float | None = None,
    harmonics: int = 3,
    path: str | Path | None = None,
    title: str = "",
) -> Figure:
    """The flapping model fitted to steady flight and to a manoeuvre, side by side (Figures 14, 12).

    Amplitude spectra of the data and the model for each output.

    **Arguments:**

    - `steady`, `manoeuvre`: the two [`fwid.FlightFit`][]s.
    - `f`: the flapping frequency [Hz], for the harmonics' marks.
    - `harmonics`: how many harmonics to mark (default 3).
    - `path`: where to save the figure (PNG); not saved when `None`.
    - `title`: the figure's title.

    **Returns:** the `matplotlib.figure.Figure`.
    """
    names = list(steady.measured)
    fig = Figure(figsize=(10, 2.0 * len(names) + 0.7), layout="constrained")
    axes = fig.subplots(len(names), 2, squeeze=False)
    for col, (label, ff) in enumerate((("steady flight", steady), ("manoeuvre", manoeuvre))):
        t = np.asarray(ff.t)
        dt = float(t[1] - t[0])
        fmax = min(60.0, 0.5 / dt)
        for row, k in enumerate(names):
            freqs, amp = amplitude_spectrum(
                np.stack([_display(k, ff.measured[k]), _display(k, ff.simulated[k])]), dt)
            _spectrum_axes(axes[row, col], freqs,
                           [("Reconstructed", amp[0], dict(color="0.2", lw=0.9)),
                            ("Estimated", amp[1], dict(color="C3", lw=1.0, ls="--"))],
                           f, harmonics, fmax, _unit(k))
            m = ff.metrics.get(k, {})
            if m:
                axes[row, col].text(0.99, 0.95, f"RMS {m['rms_pct']:.1f} % of range",
                                    ha="right", va="top", fontsize=7,
                                    transform=axes[row, col].transAxes)
            unit = _unit(k)
            axes[row, col].set_ylabel(f"|{k}| [{unit}]" if unit else f"|{k}|")
        axes[0, col].set_title(f"{label} ({t[-1] - t[0] + dt:.1f} s)", fontsize=9)
        axes[-1, col].set_xlabel("f [Hz]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(title or "Flapping model: steady flight vs manoeuvre")
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def peak_table(peaks: Mapping[str, Mapping[str, Sequence[float]]]) -> str:
    """A terminal table of the first flapping peaks, measured vs model, per signal."""
    lines = [f"{'signal':<8}{'harmonic':>9}{'measured':>12}{'model':>12}{'ratio':>8}"]
    for k, d in peaks.items():
        for i, (a, b) in enumerate(zip(d["measured"], d["model"])):
            ratio = b / a if a else float("nan")
            lines.append(f"{k:<8}{i + 1:>9}{a:>12.3e}{b:>12.3e}{ratio:>8.3f}")
    return "\n".join(lines)
