"""The combined model, Eqs. (13)-(15) in Eq. (7): cycle-averaged plus flapping aerodynamics in
the EOM, simulated with diffrax. Checked against the analytic periodic response of the linear
EOM to the Fourier forces, and for long flights."""

import time

import numpy as np
import pytest

import fwid
from fwid.models import TABLE1, TABLE4, lateral, longitudinal
from fwid.models._combined import combined, force_parts
from fwid.models._fourier import LAT_OUTPUTS, fourier_model
from fwid.report._spectra import harmonic_amplitudes

from ..paper import TABLE7

LAT_FOURIER = dict(
    ay1=4e-3, by1=-6e-3, ay2=2e-3, by2=1e-3, ay3=-1e-3, by3=5e-4,
    al1=3e-6, bl1=-2e-6, al2=1e-6, bl2=1e-6, al3=-5e-7, bl3=4e-7,
    an1=-2e-4, bn1=3e-4, an2=1e-4, bn2=-8e-5, an3=5e-5, bn3=-3e-5,
)
LON_CONSTS = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
LAT_CONSTS = dict(mass=0.0205, Ix=8e-5, Iz=3e-5, Ixz=1e-6, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
DT = 0.005


def lon_A(p, c):
    """Eq. (7) state matrix written out by hand (states q u w theta)."""
    m, Iy, g, u0, w0, th0 = (c[k] for k in ("mass", "Iy", "g", "u0", "w0", "theta0"))
    return np.array([
        [p["Mq"] / Iy, p["Mu"] / Iy, p["Mw"] / Iy, 0.0],
        [p["Xq"] / m - w0, p["Xu"] / m, p["Xw"] / m, -g * np.cos(th0)],
        [p["Zq"] / m + u0, p["Zu"] / m, p["Zw"] / m, -g * np.sin(th0)],
        [1.0, 0.0, 0.0, 0.0],
    ])


def lon_G(c):
    """How X, Z, M enter (q u w theta)'."""
    m, Iy = c["mass"], c["Iy"]
    return np.array([[0, 0, 1 / Iy], [1 / m, 0, 0], [0, 1 / m, 0], [0, 0, 0]])


def lat_A(p, c):
    m, Ix, Iz, Ixz, g, u0, w0, th0 = (c[k] for k in ("mass", "Ix", "Iz", "Ixz", "g", "u0",
                                                     "w0", "theta0"))
    Ic = Ix * Iz - Ixz**2
    L = np.array([p["Lp"], p["Lr"], p["Lv"], 0.0])
    N = np.array([p["Np"], p["Nr"], p["Nv"], 0.0])
    return np.array([
        (Iz * L + Ixz * N) / Ic,
        (Ixz * L + Ix * N) / Ic,
        [p["Yp"] / m + w0, p["Yr"] / m - u0, p["Yv"] / m, g * np.cos(th0)],
        [1.0, np.tan(th0), 0.0, 0.0],
    ])


def lat_G(c):
    m, Ix, Iz, Ixz = c["mass"], c["Ix"], c["Iz"], c["Ixz"]
    Ic = Ix * Iz - Ixz**2
    return np.array([[0, Iz / Ic, Ixz / Ic], [0, Ixz / Ic, Ix / Ic], [1 / m, 0, 0], [0, 0, 0]])


def periodic_response(A, G, coeffs, outputs, phase, w):
    """Steady periodic state of x' = A x + G F_TV(phase), phase = w t + phase0 (exact):
    `Re sum_n (j n w - A)^-1 G (b_n - j a_n) e^(j n phase)`."""
    x = np.zeros(phase.shape + (A.shape[0],))
    for n in (1, 2, 3):
        c = np.array([coeffs[f"b{o}{n}"] - 1j * coeffs[f"a{o}{n}"] for o in outputs])
        Xn = np.linalg.solve(1j * n * w * np.eye(A.shape[0]) - A, G @ c)
        x = x + np.real(Xn[None, :] * np.exp(1j * n * phase)[:, None])
    return x


def periodic_run(cycle, fourier, A, G, outputs, consts, f=12.5, phase0=0.7, n=901):
    """Simulate the combined model from the periodic state with no control input."""
    model = combined(cycle, fourier)
    t = np.arange(n) * DT
    w = 2 * np.pi * f
    phase = phase0 + w * t
    x_exact = periodic_response(A, G, fourier.params, outputs, phase, w)
    exp = fwid.Experiment(t, np.stack([np.zeros(n), phase], -1), np.zeros((n, 4)),
                          x_exact[0], consts)
    xs, ys = fwid.simulate(model, exp)
    return model, exp, np.asarray(xs), x_exact


@pytest.fixture(scope="module")
def lon_periodic():
    cycle = longitudinal(TABLE1)
    fourier = fourier_model(params=TABLE7)
    A = lon_A({k: float(v) for k, v in cycle.params.items()}, LON_CONSTS)
    return periodic_run(cycle, fourier, A, lon_G(LON_CONSTS), "xzm", LON_CONSTS)


def test_structure():
    model = combined(longitudinal(), fourier_model())
    assert model.states == ("q", "u", "w", "theta")
    assert model.outputs == model.states
    assert model.inputs == ("de", "phase")
    assert model.force_names == ("X", "Z", "M")
    assert {"Xq", "Mde", "bq", "ax1", "bm3"} <= set(model.params)
    assert set(model.local) == {"bq", "bu", "bw", "btheta"}
    # Eq. (7) plus the flapping forces: x' = f_TA(x, de) + G F_TV(phase) (Eqs. 13-15)
    model = combined(longitudinal(TABLE1), fourier_model(params=TABLE7))
    x, de, phase = np.array([0.3, -0.1, 0.2, 0.05]), 0.02, 1.234
    c = {k: np.float64(v) for k, v in LON_CONSTS.items()}
    xdot = np.asarray(model.f(x, np.array([de, phase]), model.params, c))
    A = lon_A(TABLE1, LON_CONSTS)
    B = np.array([TABLE1["Mde"] / LON_CONSTS["Iy"], TABLE1["Xde"] / LON_CONSTS["mass"],
                  TABLE1["Zde"] / LON_CONSTS["mass"], 0.0])
    F_tv = np.array([sum(TABLE7[f"a{o}{n}"] * np.sin(n * phase) + TABLE7[f"b{o}{n}"]
                         * np.cos(n * phase) for n in (1, 2, 3)) for o in "xzm"])
    np.testing.assert_allclose(xdot, A @ x + B * de + lon_G(LON_CONSTS) @ F_tv, rtol=1e-12)
    with pytest.raises(ValueError, match="not forces"):
        combined(longitudinal(), fourier_model(("Y", "L", "N")))


def test_flapping_shows_in_the_states(lon_periodic):
    """From the periodic state, the simulation stays on the exact periodic response of the
    EOM to Eq. (12): the time-varying forces are transmitted to the states."""
    model, exp, xs, x_exact = lon_periodic
    err = np.abs(xs - x_exact).max(axis=0) / np.abs(x_exact).max(axis=0)
    print("max error / amplitude (q u w theta):", np.round(err, 5))
    assert np.all(err < 5e-3)
    assert np.abs(x_exact[:, 0]).max() > 0.3  # q really oscillates (rad/s)
    # the first three flapping peaks of every state, against the analytic ones
    amp_sim = harmonic_amplitudes(xs.T, DT, 12.5)
    amp_exact = harmonic_amplitudes(x_exact.T, DT, 12.5)
    np.testing.assert_allclose(amp_sim, amp_exact, rtol=5e-3)


def test_force_parts(lon_periodic):
    model, exp, xs, _ = lon_periodic
    ta, tv = force_parts(model, xs, exp)
    total = fwid.simulate_forces(model, xs, exp)
    np.testing.assert_allclose(np.asarray(ta + tv), np.asarray(total), rtol=1e-12, atol=1e-15)
    phase = np.asarray(exp.u[:, 1])
    X_tv = sum(TABLE7[f"ax{n}"] * np.sin(n * phase) + TABLE7[f"bx{n}"] * np.cos(n * phase)
               for n in (1, 2, 3))
    np.testing.assert_allclose(np.asarray(tv[:, 0]), X_tv, rtol=1e-12, atol=1e-15)
    ta_direct = fwid.simulate_forces(longitudinal(TABLE1), xs, fwid.Experiment(
        exp.t, exp.u[:, :1], exp.z, exp.x0, exp.consts))
    np.testing.assert_allclose(np.asarray(ta), np.asarray(ta_direct), rtol=1e-12, atol=1e-15)


def test_without_flapping_it_is_the_cycle_averaged_model():
    n = 500
    t = np.arange(n) * DT
    de = np.where((t > 0.5) & (t < 0.9), 0.1, 0.0) - np.where((t >= 0.9) & (t < 1.3), 0.1, 0.0)
    cycle = longitudinal(dict(TABLE1, bq=0.01))
    model = combined(cycle, fourier_model())  # all coefficients zero
    x0 = np.array([0.1, 0.01, -0.02, 0.03])
    e2 = fwid.Experiment(t, np.stack([de, 78.5 * t], -1), np.zeros((n, 4)), x0, LON_CONSTS)
    e1 = fwid.Experiment(t, de, np.zeros((n, 4)), x0, LON_CONSTS)
    np.testing.assert_allclose(np.asarray(fwid.simulate(model, e2)[0]),
                               np.asarray(fwid.simulate(cycle, e1)[0]), rtol=1e-12, atol=1e-14)


def test_lateral_combined():
    cycle = lateral(TABLE4)
    fourier = fourier_model(LAT_OUTPUTS, params=LAT_FOURIER)
    A = lat_A({k: float(v) for k, v in cycle.params.items()}, LAT_CONSTS)
    _, _, xs, x_exact = periodic_run(cycle, fourier, A, lat_G(LAT_CONSTS), "yln", LAT_CONSTS,
                                     n=400)
    err = np.abs(xs - x_exact).max(axis=0) / np.abs(x_exact).max(axis=0)
    assert np.all(err < 1e-2), err


def test_long_flight_with_drift_stays_finite():
    """60 s at 200 Hz, the flapping frequency ramping 11.5 -> 13.2 Hz, a doublet every 10 s."""
    n = 12001
    t = np.arange(n) * DT
    f = np.linspace(11.5, 13.2, n)
    phase = np.asarray(fwid.flapping_phase(f, DT))
    s = np.mod(t, 10.0)
    de = 0.1 * ((s > 1) & (s < 1.4)) - 0.1 * ((s >= 1.4) & (s < 1.8))
    model = combined(longitudinal(dict(TABLE1, bq=0.01, bu=-0.005)),
                     fourier_model(params=TABLE7))
    exp = fwid.Experiment(t, np.stack([de, phase], -1), np.zeros((n, 4)), np.zeros(4),
                          LON_CONSTS)
    t0 = time.perf_counter()
    xs = np.asarray(fwid.simulate(model, exp)[0])
    t1 = time.perf_counter()
    xs2 = np.asarray(fwid.simulate(model, exp)[0])
    print(f"60 s at 200 Hz (12001 samples): first call {t1 - t0:.2f} s (with compilation), "
          f"then {time.perf_counter() - t1:.3f} s")
    assert np.all(np.isfinite(xs)) and np.array_equal(xs, xs2)
    assert np.abs(xs).max() < 10.0  # bounded: the cycle-averaged model is stable
    # the flapping is in the states over the whole flight (last 5 s still oscillate at f)
    tail = slice(n - 1000, n)
    amp = harmonic_amplitudes(xs[tail, 0], DT, f[tail], 1)
    assert amp[0] > 0.1
