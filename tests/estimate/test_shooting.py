"""Multiple shooting (`fwid.fit(..., method="multiple-shooting")`) on unstable vehicles.

A simulated unstable short-period model (no data files needed), FVSysID test case 8 (the
book's unstable aircraft, skipped without ../shared/flightdata), and the warning that plain
output error gives on an unstable model.
"""

import sys
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.estimate._stability import instability_warning

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from cases import tc08  # noqa: E402
from cases.textbook import fwid_model  # noqa: E402

U0 = 40.0
TRUE = dict(Zw=-1.2, Zde=-5.0, Mw=0.25, Mq=-3.0, Mde=-10.0)  # eigenvalues -5.1, +0.9


def _f(x, u, p, c):
    w, q = x
    return jnp.stack([p["Zw"] * w + U0 * q + p["Zde"] * u[0],
                      p["Mw"] * w + p["Mq"] * q + p["Mde"] * u[0]])


def _model(**values):
    return fwid.GreyBoxModel(_f, states=("w", "q"), inputs=("de",),
                             params={**TRUE, **values}, name="sp")


def _unstable_flight(seed=0):
    """8 s at 20 Hz of the unstable short period flown by a stabilising pilot: the elevator
    is a 3211 command plus feedback of w and q (as an unstable vehicle must be flown); the
    measured elevator is what was applied. Simulated by fwid (RK4) with the true values."""
    t = 0.05 * np.arange(161)
    unit, edges, signs = 0.4, (0, 3, 5, 6, 7), (1, -1, 1, -1)
    cmd = np.zeros_like(t)
    for k, sgn in enumerate(signs):
        cmd[(t >= 1 + edges[k] * unit) & (t < 1 + edges[k + 1] * unit)] = 0.02 * sgn

    def closed_loop(x, u, p, c):
        return _f(x, u + 0.05 * x[0] + 0.3 * x[1], p, c)

    loop = fwid.GreyBoxModel(closed_loop, states=("w", "q"), inputs=("cmd",), params=TRUE)
    xs, _ = fwid.simulate(loop, fwid.Experiment(t, cmd, np.zeros((len(t), 2)),
                                                x0=np.zeros(2)))
    xs = np.asarray(xs)
    de = cmd + 0.05 * xs[:, 0] + 0.3 * xs[:, 1]
    rng = np.random.default_rng(seed)
    z = xs + rng.normal(0, 0.01, xs.shape) * np.std(xs, axis=0)
    return fwid.Experiment(t, de[:, None], z, x0=np.zeros(2))


def test_multiple_shooting_recovers_an_unstable_model_where_output_error_warns():
    e = _unstable_flight()
    start = _model(Zw=-0.8, Mw=0.1, Mq=-2.0, Zde=-3.0, Mde=-6.0)  # unstable too, far off
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = fwid.fit(start, e, start="model", method="multiple-shooting", noise="diagonal")
    assert bool(res.converged)
    est = dict(zip(res.names, map(float, res.theta)))
    for k in ("Zw", "Mw", "Mq", "Mde"):
        # (the measured elevator is interpolated between samples, the pilot's feedback was
        # not: a small model error, so a relative tolerance)
        assert abs(est[k] / TRUE[k] - 1) < 0.03, (k, est[k])
    assert not any("multiple-shooting" in str(w.message) for w in caught)
    # plain output error on the same data: the start model diverges, and fwid says so
    msg = instability_warning(start, [e], ["flight"])
    assert msg is not None and "method='multiple-shooting'" in msg


def test_unknown_method_and_options_are_errors():
    e = _unstable_flight()
    with pytest.raises(ValueError, match="method must be one of"):
        fwid.fit(_model(), e, method="magic")
    with pytest.raises(TypeError, match="segments"):
        fwid.fit(_model(), e, segments=4)


@pytest.mark.skipif(not tc08.CASE.available(), reason="textbook data not found (../shared)")
def test_tc08_unstable_aircraft_within_one_percent_of_the_truth():
    """The book's start values and model (Zq fixed, as its mDefCase08): Zw, Mw, Mq within 1 %
    of the values the data were simulated with, eigenvalues -5.825 and +0.693 within 2 %."""
    r = tc08.records()[0]
    e = fwid.Experiment(r["t"], r["u"], r["z"], x0=r["x0"])
    model = fwid_model(tc08.CASE).with_free(tc08.FREE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fwid.fit(model, e, start="model", method="multiple-shooting")
    assert bool(res.converged)
    est = {k: float(v) for k, v in res.model.params.items()}
    for k, true in tc08.TRUE.items():
        assert abs(est[k] / true - 1) < 0.01, (k, est[k], true)
    eig = tc08.eigenvalues(est)
    assert np.all(np.abs(eig / np.array(tc08.TRUE_EIGENVALUES) - 1) < 0.02), eig
