"""The Figure-4-like decomposition plot (fwid.report._decomposition_plot)."""

import numpy as np
import pytest
from matplotlib.figure import Figure

import fwid  # noqa: F401  (turns on float64)
from fwid import InputError
from fwid.decomposition import decompose
from fwid.report._decomposition_plot import plot_decomposition

DT = 1 / 200
T = np.arange(400) * DT


def _raw():
    rng = np.random.default_rng(0)
    flap = np.sin(2 * np.pi * 12.8 * T)
    return {
        "t": T,
        "X": 0.05 * np.sin(2 * np.pi * 0.7 * T) + 0.3 * flap + 0.02 * rng.standard_normal(T.size),
        "Y": 0.02 * np.sin(2 * np.pi * 0.4 * T) + 0.01 * rng.standard_normal(T.size),
        "Z": -0.1 + 0.4 * flap**2 + 0.02 * rng.standard_normal(T.size),
        "f": np.full(T.size, 12.8),
    }


def test_plot_decomposition_axes_and_png(tmp_path):
    raw = _raw()
    parts = decompose(raw, DT)
    path = tmp_path / "decomposition.png"
    fig = plot_decomposition(T, raw, parts, ("X", "Y", "Z"), path=path)
    assert isinstance(fig, Figure)
    axes = fig.axes
    assert len(axes) == 9  # three signals x (filtered + averaged, flapping, spectrum)
    assert [ax.get_ylabel() for ax in axes[0::3]] == ["X", "Y", "Z"]
    assert axes[0].get_title().startswith("Filtered measurement")
    assert axes[1].get_title() == "Flapping part"
    for ax in axes[2::3]:
        assert ax.get_xscale() == "log"
        assert len(ax.patches) == 1  # the shaded flapping band
        assert ax.patches[0].get_x() == pytest.approx(5.0)
        assert len(ax.lines) == 5  # noise cut-off, raw, filtered, averaged, flapping
    assert axes[-1].get_xlabel() == "f [Hz]"
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_without_raw_and_bad_names():
    raw = _raw()
    parts = decompose(raw, DT, noise_cutoff=None)
    fig = plot_decomposition(T, None, parts, ["Z"])
    assert len(fig.axes) == 3
    assert len(fig.axes[2].lines) == 3  # no noise cut-off line, no raw spectrum
    with pytest.raises(InputError, match="'q'"):
        plot_decomposition(T, raw, parts, ["X", "q"])
    with pytest.raises(InputError, match="no signal"):
        plot_decomposition(T, raw, parts, [])
