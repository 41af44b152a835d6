"""The fit figure (residual panels, time axes on every column, the input's scale) and the
s-plane (natural-frequency circles, labelled damping rays, many flights apart)."""

import numpy as np

import fwid  # noqa: F401  (float64)
from fwid import FlightFit
from fwid.report import plot_flight_fit, plot_poles


def _flight_fit():
    t = np.arange(200) * 0.01
    s = {k: np.sin(t * (i + 1)) for i, k in enumerate(("q", "u", "w", "theta"))}
    f = {k: np.cos(t * (i + 1)) for i, k in enumerate(("X", "Z", "M"))}
    m = {k: dict(corr=1.0, r2=1.0, rms=0.0, rms_pct=0.0) for k in [*s, *f]}
    return FlightFit("a/lon_0.csv", t, {"de": np.deg2rad(2) * np.sign(np.sin(3 * t))}, s,
                     {k: 0.9 * v for k, v in s.items()}, f, {k: 0.8 * v for k, v in f.items()},
                     m, {})


def test_fit_figure_has_residuals_and_time_axes(tmp_path):
    fig = plot_flight_fit(_flight_fit(), path=tmp_path / "fit.png")
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 2 * (4 + 3)  # a residual panel under each of 4 states, 3 forces
    residuals = [ax for ax in visible if ax.get_ylabel() == "resid."]
    assert len(residuals) == 7
    line = residuals[0].get_lines()[0]
    np.testing.assert_allclose(line.get_ydata(), np.rad2deg(0.1 * np.sin(line.get_xdata())))
    assert sum(ax.get_xlabel() == "t [s]" for ax in visible) == 2  # both columns
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any("range 4 deg" in lab for lab in labels), labels
    assert (tmp_path / "fit.png").stat().st_size > 0


def test_poles_circles_rays_and_many_flights():
    rng = np.random.default_rng(0)
    eigs = [np.array([-2 + 5j, -2 - 5j, -8.0]) + rng.normal(0, 0.2) for _ in range(16)]
    fig = plot_poles(eigs, [f"f{i}" for i in range(16)], highlight=0)
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert any(t.startswith("\u03b6=") for t in texts) and any(t.startswith("\u03c9n=") for t in texts)
    marks = [ln for ln in ax.get_lines() if ln.get_label() in {f"f{i}" for i in range(16)}]
    styles = {(ln.get_marker(), ln.get_color()) for ln in marks}
    assert len(styles) == 16  # every flight told apart
    assert len(fig.legends[0].get_texts()) == 16


def test_overview_one_row_a_flight_or_the_worst_and_best(tmp_path):
    from fwid.report import plot_fits_overview
    from fwid.report._overview import overview_rows

    fits = []
    for i in range(12):
        ff = _flight_fit()
        fits.append(FlightFit(f"f{i}", ff.t, ff.inputs, ff.measured, ff.simulated, {}, {},
                              {k: dict(corr=1.0, r2=i / 12, rms=0.0, rms_pct=0.0)
                               for k in ff.measured}, {}))
    fig = plot_fits_overview(fits[:3], path=tmp_path / "fits.png")
    assert len(fig.axes) == 3 * 4 and (tmp_path / "fits.png").stat().st_size > 0
    rows = overview_rows(fits, most=6)
    assert [(rank, f.name) for rank, f in rows] == [
        ("worst", "f0"), ("worst", "f1"), ("worst", "f2"),
        ("best", "f9"), ("best", "f10"), ("best", "f11")]
    assert len(plot_fits_overview(fits, most=6).axes) == 6 * 4
