"""The reconstruction figure: its series drawn through their per-slice extremes (every glitch
kept), and a figure redrawn for another take equal to one drawn afresh."""

from types import SimpleNamespace

import numpy as np

from fwid.report._reconstruction import envelope, plot_reconstruction


def test_envelope_keeps_every_extreme_in_time_order():
    rng = np.random.default_rng(0)
    t = np.arange(12000) * 0.005
    y = np.sin(2 * np.pi * 12 * t) + 0.01 * rng.standard_normal(t.size)
    y[7777], y[123] = 9.0, -7.0  # glitches
    y[500] = np.nan
    te, ye = envelope(t, y, points=300)
    assert len(te) <= 600 and np.all(np.diff(te) > 0)
    assert 9.0 in ye and -7.0 in ye
    # each slice's extremes are there: the envelope's max over a slice equals the data's
    edges = np.linspace(0, t.size, 301).astype(int)
    for a, b in zip(edges[:-1:37], edges[1::37]):
        sel = (te >= t[a]) & (te <= t[b - 1])
        assert np.nanmax(y[a:b]) == ye[sel].max() and np.nanmin(y[a:b]) == ye[sel].min()
    short = np.arange(10.0)
    assert np.array_equal(envelope(short, short)[1], short)


def _flight(seed, n=3000, gyro=True):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.005
    cols = {"t": t}
    for k in ("x", "y", "z", "phi", "theta", "psi", "p", "q", "r"):
        cols[k] = np.cumsum(rng.standard_normal(n)) * 1e-3
    quat = np.tile([1.0, 0, 0, 0], (n, 1))
    tracked = rng.random(n) > 0.01
    raw = {"t": t, "pos": np.stack([cols[k] for k in "xyz"], 1), "quat": quat,
           "tracked": tracked, "gyro": rng.standard_normal((n, 3)) if gyro else None}
    entry = {"flight": f"f{seed}.csv", "dropouts": [[1.0, 1.02], [7.5, 7.6]],
             "gyro_bias_rad_s": [0.0, 0.0, 0.0], "clock": None}
    return SimpleNamespace(columns=cols, raw=raw, entry=entry)


def test_redrawn_figure_equals_a_fresh_one(tmp_path):
    a, b = _flight(1), _flight(2)
    fresh = plot_reconstruction(b)
    reused = plot_reconstruction(b, figure=plot_reconstruction(a))
    for fa, ra in zip(fresh.axes, reused.axes):
        for lf, lr in zip(fa.get_lines(), ra.get_lines()):
            assert np.array_equal(lf.get_xdata(), lr.get_xdata())
            assert np.array_equal(lf.get_ydata(), lr.get_ydata())
        assert fa.get_ylim() == ra.get_ylim()
        assert len(ra.collections) == 1  # the bands of this take only
    assert reused._suptitle.get_text() == fresh._suptitle.get_text()
    # a take without a gyro gets a figure of its own kind
    other = plot_reconstruction(_flight(3, gyro=False), figure=reused, path=tmp_path / "f.png")
    assert other is not reused and (tmp_path / "f.png").stat().st_size > 0
