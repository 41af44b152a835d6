"""fit_metrics against hand computations."""

import numpy as np
import pytest

from fwid.validate import fit_metrics


def test_perfect_fit():
    t = np.linspace(0, 1, 50)
    z = np.stack([np.sin(3 * t), t**2 - 0.2], axis=-1)
    m = fit_metrics(z, z.copy(), ["a", "b"])
    assert list(m) == ["a", "b"]
    for name in m:
        assert m[name]["corr"] == pytest.approx(1.0, abs=1e-12)
        assert m[name]["r2"] == 1.0
        assert m[name]["rms"] == 0.0
        assert m[name]["rms_pct"] == 0.0


def test_known_offset():
    z = np.array([0.0, 1.0, 2.0, 3.0, 4.0])[:, None]
    y = z + 0.5
    m = fit_metrics(z, y, ["x"])["x"]
    assert m["rms"] == pytest.approx(0.5, rel=1e-14)
    assert m["rms_pct"] == pytest.approx(100 * 0.5 / 4.0, rel=1e-14)
    assert m["corr"] == pytest.approx(1.0, abs=1e-12)  # an offset keeps the shape
    # sst = 10, sse = 5 * 0.25
    assert m["r2"] == pytest.approx(1 - 1.25 / 10.0, rel=1e-14)


def test_hand_computed_values():
    z = np.array([1.0, 3.0, 2.0, 5.0])
    y = np.array([1.5, 2.0, 2.0, 4.0])
    m = fit_metrics(z[:, None], y[:, None], ["q"])["q"]
    e = z - y  # -0.5, 1, 0, 1
    assert m["rms"] == pytest.approx(np.sqrt((0.25 + 1 + 0 + 1) / 4), rel=1e-14)
    assert m["rms_pct"] == pytest.approx(100 * np.sqrt(2.25 / 4) / 4.0, rel=1e-14)
    zm, ym = z.mean(), y.mean()  # 2.75, 2.375
    corr = np.sum((z - zm) * (y - ym)) / np.sqrt(np.sum((z - zm) ** 2) * np.sum((y - ym) ** 2))
    assert m["corr"] == pytest.approx(corr, rel=1e-12)
    assert m["r2"] == pytest.approx(1 - np.sum(e**2) / np.sum((z - zm) ** 2), rel=1e-14)


def test_r2_negative_for_a_bad_model_and_anticorrelation():
    z = np.sin(np.linspace(0, 6, 100))[:, None]
    m = fit_metrics(z, -z, ["x"])["x"]
    assert m["corr"] == pytest.approx(-1.0, abs=1e-12)
    assert m["r2"] == pytest.approx(1 - 4.0 * np.sum(z**2) / np.sum((z - z.mean()) ** 2))
    assert m["r2"] < 0


def test_constant_signals_give_nan_not_errors():
    z = np.ones((10, 1))
    y = np.linspace(0, 1, 10)[:, None]
    m = fit_metrics(z, y, ["c"])["c"]
    assert np.isnan(m["corr"]) and np.isnan(m["r2"]) and np.isnan(m["rms_pct"])
    assert m["rms"] == pytest.approx(np.sqrt(np.mean((1 - y) ** 2)))
    # a constant model output: no correlation (NaN, or ~0 when rounding makes it non-constant)
    m2 = fit_metrics(y, np.zeros((10, 1)) + 0.3, ["flat model"])["flat model"]
    assert np.isnan(m2["corr"]) or abs(m2["corr"]) < 1e-12
