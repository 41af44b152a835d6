"""Amplitude spectra, flapping peaks, and the figures of Sections V-VI (Figures 12-17)."""

import numpy as np
import pytest
from matplotlib.figure import Figure

import fwid  # noqa: F401  (float64)
from fwid import FlightFit
from fwid.report._spectra import (
    amplitude_spectrum,
    harmonic_amplitudes,
    peak_table,
    plot_steady_vs_manoeuvre,
    plot_superposition,
    plot_time_and_spectrum,
)

DT = 0.005
AMPS = np.array([0.09, 0.04, 0.02])


def three_harmonics(phase, amps=AMPS, shifts=(0.3, -1.0, 2.0)):
    return sum(a * np.sin((k + 1) * phase + s) for k, (a, s) in enumerate(zip(amps, shifts)))


def test_amplitude_spectrum_peak_height():
    n = 1000
    t = np.arange(n) * DT
    x = 0.7 + 0.05 * np.sin(2 * np.pi * 12.0 * t)  # 12 Hz is bin 60 of 1000 at 200 Hz
    freqs, amp = amplitude_spectrum(x, DT)
    k = np.argmax(amp)
    assert freqs[k] == pytest.approx(12.0)
    assert amp[k] == pytest.approx(0.05, rel=1e-3)
    assert freqs[0] > 0  # f = 0 left out
    _, amp2 = amplitude_spectrum(np.stack([x, 2 * x]), DT)
    np.testing.assert_allclose(amp2[1], 2 * amp2[0])


def test_harmonic_amplitudes_steady_with_body_motion_and_noise():
    n = 901
    t = np.arange(n) * DT
    rng = np.random.default_rng(0)
    slow = 0.5 * np.exp(-((t - 2.0) / 0.4) ** 2) + 0.2 * t  # body motion, 10x the flapping
    x = slow + three_harmonics(2 * np.pi * 12.5 * t + 0.4) + 0.002 * rng.standard_normal(n)
    amp = harmonic_amplitudes(x, DT, 12.5)
    np.testing.assert_allclose(amp, AMPS, rtol=0.01)
    # without removing the slow motion first, the leakage is visible
    raw = harmonic_amplitudes(x, DT, 12.5, cutoff=None)
    assert np.max(np.abs(raw / AMPS - 1)) > np.max(np.abs(amp / AMPS - 1))


def test_harmonic_amplitudes_follow_a_drifting_frequency():
    n = 901
    f = np.linspace(11.5, 13.2, n)
    phase = np.asarray(fwid.flapping_phase(f, DT))
    x = np.stack([three_harmonics(phase), 2 * three_harmonics(phase)])
    amp = harmonic_amplitudes(x, DT, f)
    assert amp.shape == (2, 3)
    np.testing.assert_allclose(amp, np.stack([AMPS, 2 * AMPS]), rtol=1e-3)
    # a single (mean) frequency smears the drifting lines and misses most of them
    naive = harmonic_amplitudes(x[0], DT, float(f.mean()))
    assert np.all(naive < 0.6 * AMPS)


def _flight_fit(with_forces=False):
    n = 600
    t = np.arange(n) * DT
    phase = 2 * np.pi * 12.5 * t
    meas = {"X": three_harmonics(phase), "Z": 0.5 * three_harmonics(phase + 1)}
    sim = {k: 0.95 * v for k, v in meas.items()}
    fm = fs = {}
    if with_forces:
        fm, fs = {"M": 0.01 * np.sin(phase)}, {"M": 0.011 * np.sin(phase)}
    metrics = fwid.fit_metrics(np.stack([*meas.values(), *fm.values()], -1),
                               np.stack([*sim.values(), *fs.values()], -1),
                               list(meas) + list(fm))
    de = np.where(t > 1.5, 0.1, 0.0)
    return FlightFit(name="f.csv", t=t, inputs={"de": de, "phase": phase}, measured=meas,
                     simulated=sim, forces_measured=fm, forces_simulated=fs, metrics=metrics,
                     local_params={})


def test_time_and_spectrum_figure(tmp_path):
    ff = _flight_fit(with_forces=True)
    fig = plot_time_and_spectrum(ff, f=12.5, path=tmp_path / "fig12.png", title="Figure 12")
    assert isinstance(fig, Figure)
    assert (tmp_path / "fig12.png").stat().st_size > 10_000
    axes = fig.get_axes()
    assert len(axes) == 9  # X, Z and M: time, zoom and spectrum each
    full, zoom, spec = axes[:3]
    assert spec.get_xscale() == "log"
    # the zoom shows 4 flapping cycles in the middle of the record; the full trace shades them
    lo, hi = zoom.get_xlim()
    assert hi - lo == pytest.approx(4 / 12.5) and lo + hi == pytest.approx(599 * DT)
    assert zoom.get_lines()[0].get_xdata().size == pytest.approx(4 / 12.5 / DT, abs=2)
    assert len(full.patches) == 1
    assert zoom.get_title().startswith("RMS ") and " N (" in zoom.get_title()
    # units on the spectra: the force's unit on the amplitude, Hz on the frequency
    assert [a.get_ylabel() for a in axes[2::3]] == ["|X| [N]", "|Z| [N]", "|M| [N m]"]
    assert axes[-1].get_xlabel() == "f [Hz]"
    # the harmonic marks are at n f
    marks = sorted(line.get_xdata()[0] for line in spec.get_lines() if line.get_linestyle() == ":")
    np.testing.assert_allclose(marks, [12.5, 25.0, 37.5])


def test_superposition_and_steady_figures(tmp_path):
    n = 800
    t = np.arange(n) * DT
    ta = {"X": 0.1 * np.sin(2 * np.pi * 0.8 * t)}
    tv = {"X": three_harmonics(2 * np.pi * 12.5 * t)}
    meas = {"X": ta["X"] + tv["X"]}
    fig = plot_superposition(t, meas, ta, tv, f=12.5, path=tmp_path / "fig15.png")
    assert len(fig.get_axes()) == 1 and (tmp_path / "fig15.png").exists()
    labels = [line.get_label() for line in fig.get_axes()[0].get_lines()]
    assert {"Measured", "TA model", "TV model", "TA + TV"} <= set(labels)
    ff = _flight_fit()
    fig = plot_steady_vs_manoeuvre(ff, ff, f=12.5, path=tmp_path / "fig14.png")
    assert len(fig.get_axes()) == 4 and (tmp_path / "fig14.png").exists()
    assert fig.get_axes()[0].get_ylabel() == "|X| [N]"


def test_peak_table():
    text = peak_table({"q": {"measured": [1.0, 0.5, 0.1], "model": [0.99, 0.5, 0.11]}})
    assert "q" in text and "0.990" in text and len(text.splitlines()) == 4
