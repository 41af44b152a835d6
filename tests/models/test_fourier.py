"""The Fourier-series model of the flapping forces, Eq. (12): structure, least squares, ML fit,
phase alignment, and a drifting flapping frequency.

Test signals are Eq. (12) written out with numpy (Table 7's coefficients) plus white noise.
"""

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.identification import flapping_data
from fwid.data import Flight
from fwid.models._fourier import (
    estimate_phase_offset,
    fourier_least_squares,
    fourier_model,
    fourier_param_names,
    fourier_regressors,
    fourier_series,
    shift_phase,
)

from ..paper import TABLE7

SIGMA = np.array([0.01, 0.01, 5e-4])  # force noise [N, N, N m]
DT = 0.005


def eq12(phase, p=TABLE7, outputs="xzm"):
    """Eq. (12) by hand."""
    return np.stack([
        sum(p[f"a{o}{n}"] * np.sin(n * phase) + p[f"b{o}{n}"] * np.cos(n * phase)
            for n in (1, 2, 3))
        for o in outputs
    ], axis=-1)


def flapping_flight(f, *, phase0=0.0, seed=0, name="flap.csv", sigma=SIGMA, first_input=0,
                    extra=None):
    """A flight whose forces are exactly Eq. (12) at the true phase, plus white noise."""
    n = f.shape[0]
    t = np.arange(n) * DT
    # exact phase of a piecewise-linear f (what the trapezoidal rule integrates exactly)
    phase = phase0 + np.concatenate([[0.0], np.cumsum(np.pi * DT * (f[1:] + f[:-1]))])
    F = eq12(phase)
    if extra is not None:
        F = F + extra
    rng = np.random.default_rng(seed)
    z = F + sigma * rng.standard_normal(F.shape)
    cols = {"X": z[:, 0] + 0.17, "Z": z[:, 1] - 0.05, "M": z[:, 2], "f": f,
            "de": 0.04 + np.zeros(n)}
    trim = {"X0": 0.17, "Z0": -0.05, "M0": 0.0, "de0": 0.04}
    return Flight(t=jnp.asarray(t), columns={k: jnp.asarray(v) for k, v in cols.items()},
                  trim={k: jnp.asarray(v) for k, v in trim.items()}, vehicle=None, name=name,
                  first_input=first_input)


def fit_flight(flight, phase_shift=0.0):
    t, phase, z = flapping_data(flight)
    model = fourier_model()
    exp = fwid.Experiment(t, phase[:, None] + phase_shift, z, x0=np.zeros(0))
    return fwid.fit(model, exp, start=fourier_least_squares(model, exp)), exp


@pytest.fixture(scope="module")
def steady_fit():
    flight = flapping_flight(np.full(901, 12.5), seed=3)
    return fit_flight(flight)


def test_parameter_names_follow_the_contract():
    names = fourier_param_names(("X", "Z", "M"))
    assert names[:6] == ("ax1", "bx1", "ax2", "bx2", "ax3", "bx3")
    assert names[-2:] == ("am3", "bm3") and len(names) == 18
    assert fourier_param_names(("Y", "L", "N"), 2) == (
        "ay1", "by1", "ay2", "by2", "al1", "bl1", "al2", "bl2", "an1", "bn1", "an2", "bn2")
    model = fourier_model()
    assert model.states == () and model.inputs == ("phase",)
    assert model.outputs == ("X", "Z", "M") and tuple(model.free) == names


def test_series_is_eq12():
    phase = np.linspace(0, 20, 333)
    np.testing.assert_allclose(np.asarray(fourier_series(phase, TABLE7)), eq12(phase),
                               rtol=1e-12, atol=1e-15)
    # for a constant f the phase is 2 pi f t: the paper's Eq. (12) exactly
    t = np.arange(400) * DT
    phase = np.asarray(fwid.flapping_phase(np.full(400, 12.5), DT))
    np.testing.assert_allclose(phase, 2 * np.pi * 12.5 * t, rtol=1e-12, atol=1e-9)
    # the static model's simulation is the series at each sample
    model = fourier_model(params=TABLE7)
    exp = fwid.Experiment(t, phase[:, None], np.zeros((400, 3)), x0=np.zeros(0))
    _, ys = fwid.simulate(model, exp)
    np.testing.assert_allclose(np.asarray(ys), eq12(phase), rtol=1e-12, atol=1e-15)
    assert fourier_regressors(phase).shape == (400, 6)


def test_shift_phase_is_a_phase_advance():
    phase = np.linspace(0, 10, 200)
    for d in (0.3, -2.0, 3.1):
        shifted = shift_phase(TABLE7, d)
        np.testing.assert_allclose(eq12(phase, shifted), eq12(phase + d), atol=1e-14)


def test_coefficients_within_their_uncertainty(steady_fit):
    """Table 7 comes back: every coefficient within 3 of its reported standard deviations,
    and those deviations are the right size (white noise: sigma sqrt(2 / N))."""
    r, exp = steady_fit
    assert bool(r.converged)
    true = np.array([TABLE7[k] for k in r.names])
    z = (np.asarray(r.theta) - true) / np.asarray(r.std)
    print("coefficient error / std:", np.round(z, 2), "max", np.abs(z).max().round(2))
    assert np.all(np.abs(z) < 3.0)
    assert 0.4 < np.sqrt(np.mean(z**2)) < 1.8  # the std are neither inflated nor too small
    expected = np.repeat(SIGMA, 6) * np.sqrt(2.0 / exp.n)
    np.testing.assert_allclose(np.asarray(r.std_cr), expected, rtol=0.15)
    # the ML estimate of a linear-in-parameters model is the least-squares one
    ls = fourier_least_squares(fourier_model(), exp)
    np.testing.assert_allclose(np.asarray(r.theta),
                               [float(ls.params[k]) for k in r.names], rtol=1e-3, atol=1e-6)


def test_wrong_phase_is_detected(steady_fit):
    """The same data fitted against a phase that runs 1 % fast: the errors are far outside
    the reported uncertainty (the check above can fail)."""
    flight = flapping_flight(np.full(901, 12.5), seed=3)
    t, phase, z = flapping_data(flight)
    model = fourier_model()
    exp = fwid.Experiment(t, 1.01 * phase[:, None], z, x0=np.zeros(0))
    r = fwid.fit(model, exp, start=fourier_least_squares(model, exp))
    true = np.array([TABLE7[k] for k in r.names])
    assert np.max(np.abs((np.asarray(r.theta) - true) / np.asarray(r.std))) > 10


def test_phase_offset_is_recovered(steady_fit):
    """A validation flight that starts at another point of the stroke (Section V.A)."""
    r, _ = steady_fit
    for true_offset in (1.2, -2.9, 3.0):
        flight = flapping_flight(np.full(700, 12.3), phase0=true_offset, seed=7)
        t, phase, z = flapping_data(flight)
        d = estimate_phase_offset(r.model, phase, z)
        err = (d - true_offset + np.pi) % (2 * np.pi) - np.pi
        assert abs(err) < 0.01, (true_offset, d)
        aligned = r.model.with_params(shift_phase(r.model.params, d))
        exp = fwid.Experiment(t, phase[:, None], z, x0=np.zeros(0))
        resid = z - np.asarray(fwid.simulate(aligned, exp)[1])
        np.testing.assert_array_less(resid.std(axis=0), 1.15 * SIGMA)


def test_drifting_frequency_stays_in_phase():
    """f ramps 11.5 -> 13.2 Hz: driven by the phase, the model's residual RMS is within 10 %
    of a constant-frequency flight's; driven by 2 pi mean(f) t it is not."""
    n = 901
    const = flapping_flight(np.full(n, 12.35), seed=11)
    drift = flapping_flight(np.linspace(11.5, 13.2, n), seed=11)
    rc, ec = fit_flight(const)
    rd, ed = fit_flight(drift)
    rms_c = np.sqrt(np.mean((np.asarray(ec.z) - np.asarray(fwid.simulate(rc.model, ec)[1])) ** 2,
                            axis=0))
    rms_d = np.sqrt(np.mean((np.asarray(ed.z) - np.asarray(fwid.simulate(rd.model, ed)[1])) ** 2,
                            axis=0))
    ratio = rms_d / rms_c
    print("drift / constant residual RMS (X, Z, M):", np.round(ratio, 4))
    assert np.all(ratio <= 1.10)
    # control: one frequency for the whole flight, as 2 pi f t with the mean f
    t = np.asarray(ed.t)
    naive = fwid.Experiment(t, (2 * np.pi * 12.35 * t)[:, None], ed.z, x0=np.zeros(0))
    model = fourier_model()
    rn = fwid.fit(model, naive, start=fourier_least_squares(model, naive))
    rms_n = np.sqrt(np.mean((np.asarray(naive.z) - np.asarray(fwid.simulate(rn.model, naive)[1]))
                            ** 2, axis=0))
    print("naive 2 pi f t / constant residual RMS:", np.round(rms_n / rms_c, 2))
    assert np.all(rms_n / rms_c > 2.0)


def test_missing_frequency_column_is_named():
    flight = flapping_flight(np.full(300, 12.5))
    cols = dict(flight.columns)
    cols.pop("f")
    bad = Flight(t=flight.t, columns=cols, trim=flight.trim, vehicle=None, name="nof.csv")
    with pytest.raises(fwid.FlightDataError, match="'f'.*nof.csv|nof.csv.*'f'"):
        flapping_data(bad)
