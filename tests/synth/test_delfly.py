"""The simulated DelFly: parameters, eigenvalues (paper Tables 3, 6), integration, flapping,
measurement and injected effects."""

import numpy as np
import pytest
from scipy import integrate, signal

from fwid.synth import (
    ALL_PARAMS,
    DELFLY,
    EFFECTS,
    NOISE,
    STATES,
    Effect,
    simulate_flight,
)

G = 9.81
TABLE3 = np.array([-10.9638, -1.3538 + 5.6483j, -1.3538 - 5.6483j, -3.3945])
TABLE6 = np.array([-1.3186 + 5.7559j, -1.3186 - 5.7559j, -5.0708, -9.1591])

TABLE1 = {
    "Xq": 3.05e-03,
    "Xu": -3.39e-02,
    "Xw": 1.81e-02,
    "Xde": 2.53e-02,
    "Zq": -1.31e-02,
    "Zu": -3.21e-02,
    "Zw": -7.74e-02,
    "Zde": -9.67e-02,
    "Mq": -1.03e-03,
    "Mu": 3.90e-03,
    "Mw": 2.59e-03,
    "Mde": -6.96e-03,
}
TABLE4 = {
    "Yp": 6.54e-04,
    "Yr": -2.59e-03,
    "Yv": -9.92e-02,
    "Ydr": -6.96e-02,
    "Lp": -7.14e-06,
    "Lr": 3.09e-05,
    "Lv": -4.47e-05,
    "Ldr": 6.89e-05,
    "Np": -1.98e-05,
    "Nr": -4.79e-04,
    "Nv": -1.45e-03,
    "Ndr": -2.10e-03,
}
TABLE7 = {
    "ax1": -7.09e-03,
    "bx1": 8.89e-02,
    "ax2": 3.09e-02,
    "bx2": 2.75e-02,
    "ax3": 7.32e-03,
    "bx3": 1.83e-02,
    "az1": 4.02e-02,
    "bz1": -5.64e-02,
    "az2": -5.51e-03,
    "bz2": 4.24e-02,
    "az3": 1.42e-02,
    "bz3": 1.29e-02,
    "am1": -3.58e-04,
    "bm1": 3.20e-03,
    "am2": -5.15e-04,
    "bm2": 2.69e-03,
    "am3": 5.44e-04,
    "bm3": 8.35e-04,
}


# --------------------------------------------------------------------------- independent EOM
def eom_matrices(p):
    """Eqs. 7-9 written out again from the paper, independently of fwid.synth: 9 states
    [q u w theta p r v phi psi], inputs [de dr], 6 extra loads [X Y Z L M N]."""
    m, th, u0, w0 = p.mass, p.theta0, p.u0, p.w0
    Ic = p.Ix * p.Iz - p.Ixz**2
    A = np.zeros((9, 9))
    B = np.zeros((9, 2))
    A[0, :3] = np.array([p.Mq, p.Mu, p.Mw]) / p.Iy
    A[1, :4] = [p.Xq / m - w0, p.Xu / m, p.Xw / m, -G * np.cos(th)]
    A[2, :4] = [p.Zq / m + u0, p.Zu / m, p.Zw / m, -G * np.sin(th)]
    A[3, 0] = 1.0
    Lrow = np.array([p.Lp, p.Lr, p.Lv])
    Nrow = np.array([p.Np, p.Nr, p.Nv])
    A[4, 4:7] = (p.Iz * Lrow + p.Ixz * Nrow) / Ic
    A[5, 4:7] = (p.Ixz * Lrow + p.Ix * Nrow) / Ic
    A[6, 4:8] = [p.Yp / m + w0, p.Yr / m - u0, p.Yv / m, G * np.cos(th)]
    A[7, 4:6] = [1.0, np.tan(th)]
    A[8, 5] = 1.0 / np.cos(th)
    B[0, 0], B[1, 0], B[2, 0] = p.Mde / p.Iy, p.Xde / m, p.Zde / m
    B[4, 1] = (p.Iz * p.Ldr + p.Ixz * p.Ndr) / Ic
    B[5, 1] = (p.Ixz * p.Ldr + p.Ix * p.Ndr) / Ic
    B[6, 1] = p.Ydr / m
    Gm = np.zeros((9, 6))
    Gm[0, 4] = 1 / p.Iy
    Gm[1, 0] = Gm[2, 2] = Gm[6, 1] = 1 / m
    Gm[4, 3], Gm[4, 5], Gm[5, 3], Gm[5, 5] = p.Iz / Ic, p.Ixz / Ic, p.Ixz / Ic, p.Ix / Ic
    return A, B, Gm


def table7_loads(phase):
    """Eq. 12 with Table 7 for X, Z, M (and DELFLY's lateral coefficients), [X Y Z L M N]."""
    out = np.zeros(np.shape(phase) + (6,))
    for i, c in enumerate("xyzlmn"):
        for n in (1, 2, 3):
            a = TABLE7.get(f"a{c}{n}", getattr(DELFLY, f"a{c}{n}"))
            b = TABLE7.get(f"b{c}{n}", getattr(DELFLY, f"b{c}{n}"))
            out[..., i] += a * np.sin(n * phase) + b * np.cos(n * phase)
    return out


def perturbation_states(fl):
    trim = fl["meta"]["trim"]
    return np.stack([fl[s] - trim[s + "0"] for s in STATES], axis=1)


def sorted_eigs(A):
    return np.sort_complex(np.linalg.eigvals(A))


# --------------------------------------------------------------------------- parameters
def test_tables_1_4_7_values_and_names():
    params = DELFLY.params()
    assert tuple(params) == ALL_PARAMS
    for table in (TABLE1, TABLE4, TABLE7):
        for k, v in table.items():
            assert params[k] == v, k
    lat_flap = [f"{ab}{c}{n}" for c in "yln" for n in (1, 2, 3) for ab in "ab"]
    assert all(k in params for k in lat_flap)


def test_plausible_vehicle_and_trim():
    assert 0.016 <= DELFLY.mass <= 0.025
    assert np.radians(65) <= DELFLY.theta0 <= np.radians(85)
    assert 0.3 <= np.hypot(DELFLY.u0, DELFLY.w0) <= 1.5
    assert DELFLY.Ix > 0 and DELFLY.Iy > 0 and DELFLY.Iz > 0
    assert DELFLY.Ix * DELFLY.Iz - DELFLY.Ixz**2 > 0


@pytest.mark.parametrize("axis, table", [("lon", TABLE3), ("lat", TABLE6)])
def test_eigenvalues_reproduce_paper_tables(axis, table):
    A, _, _ = eom_matrices(DELFLY)
    blk = slice(0, 4) if axis == "lon" else slice(4, 8)
    for eigs in (sorted_eigs(A[blk, blk]), DELFLY.eigenvalues(axis)):
        want = np.sort_complex(table)
        np.testing.assert_allclose(eigs, want, rtol=1e-3)
        assert np.max(np.abs(eigs - want) / np.abs(want)) < 1e-6  # exact to print precision


def test_package_matrices_match_paper_equations():
    A, B, _ = eom_matrices(DELFLY)
    Al, Bl = DELFLY.lon_matrices()
    At, Bt = DELFLY.lat_matrices()
    np.testing.assert_allclose(Al, A[:4, :4], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(At, A[4:8, 4:8], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(Bl[:, 0], B[:4, 0], rtol=1e-12)
    np.testing.assert_allclose(Bt[:, 0], B[4:8, 1], rtol=1e-12)


# --------------------------------------------------------------------------- integration
def rk4_reference(A, B, t, u):
    """Fixed-step RK4 at the sample step, inputs linear between samples."""
    x = np.zeros((len(t), A.shape[0]))
    h = t[1] - t[0]
    for k in range(len(t) - 1):
        um = 0.5 * (u[k] + u[k + 1])
        k1 = A @ x[k] + B @ u[k]
        k2 = A @ (x[k] + h / 2 * k1) + B @ um
        k3 = A @ (x[k] + h / 2 * k2) + B @ um
        k4 = A @ (x[k] + h * k3) + B @ u[k + 1]
        x[k + 1] = x[k] + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def clean_kw():
    return {"flapping": False, "ripple": False, "noise": 0.0}


@pytest.mark.parametrize("axis", ["lon", "lat"])
def test_clean_flight_is_exactly_rk4_with_linear_inputs(axis):
    fl = simulate_flight(axis=axis, input="3211", **clean_kw())
    trim = fl["meta"]["trim"]
    u = np.stack([fl["de"] - trim["de0"], fl["dr"] - trim["dr0"]], axis=1)
    A, B, _ = eom_matrices(DELFLY)
    x_ref = rk4_reference(A, B, fl["t"], u)
    x = perturbation_states(fl)
    scale = np.abs(x_ref).max(axis=0) + 1e-300
    assert np.max(np.abs(x - x_ref).max(axis=0)[scale > 1e-12] / scale[scale > 1e-12]) < 1e-10
    # the other axis stays exactly at trim
    other = slice(4, 9) if axis == "lon" else slice(0, 4)
    assert np.all(x[:, other] == 0.0)


@pytest.mark.parametrize("axis, substeps", [("lon", 1), ("lat", 1), ("lon", 4)])
def test_clean_flight_matches_solve_ivp(axis, substeps):
    fl = simulate_flight(axis=axis, input="doublet", substeps=substeps, **clean_kw())
    t = fl["t"]
    trim = fl["meta"]["trim"]
    u = np.stack([fl["de"] - trim["de0"], fl["dr"] - trim["dr0"]], axis=1)
    A, B, _ = eom_matrices(DELFLY)

    def rhs(tt, x):
        return A @ x + B @ np.array([np.interp(tt, t, u[:, 0]), np.interp(tt, t, u[:, 1])])

    sol = integrate.solve_ivp(
        rhs,
        (t[0], t[-1]),
        np.zeros(9),
        t_eval=t,
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        max_step=t[1] - t[0],
    )
    x = perturbation_states(fl)
    scale = np.abs(sol.y.T).max(axis=0)
    active = scale > 1e-9
    err = np.abs(x - sol.y.T).max(axis=0)[active] / scale[active]
    assert np.max(err) < (1e-6 if substeps == 1 else 1e-8)


def test_flapping_flight_matches_solve_ivp():
    fl = simulate_flight(axis="lon", noise=0.0, ripple=False, substeps=8, duration=2.5)
    meta = fl["meta"]
    t = fl["t"]
    trim = meta["trim"]
    u = np.stack([fl["de"] - trim["de0"], fl["dr"] - trim["dr0"]], axis=1)
    A, B, Gm = eom_matrices(DELFLY)
    phase = meta["flap"].phase

    def rhs(tt, x):
        uu = np.array([np.interp(tt, t, u[:, 0]), np.interp(tt, t, u[:, 1])])
        return A @ x + B @ uu + Gm @ table7_loads(phase(tt))

    x = perturbation_states(fl)
    sol = integrate.solve_ivp(
        rhs,
        (t[0], t[-1]),
        x[0],
        t_eval=t,
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        max_step=0.25 * (t[1] - t[0]),
    )
    scale = np.abs(sol.y.T).max(axis=0)
    err = np.abs(x - sol.y.T).max(axis=0) / scale
    assert np.max(err) < 1e-6


def test_initial_state_option():
    fl = simulate_flight(amplitude=0.0, initial={"q": 0.3, "v": 0.1}, **clean_kw())
    x = perturbation_states(fl)
    assert x[0, 0] == 0.3 and x[0, 6] == 0.1
    assert np.abs(x[-1, :8]).max() < 0.01  # stable: decays (psi, an integrator, excepted)
    with pytest.raises(ValueError):
        simulate_flight(initial={"nope": 1.0})


# --------------------------------------------------------------------------- flapping
def trapezoid_phase(t, f):
    return np.concatenate([[0.0], np.cumsum(np.pi * (f[1:] + f[:-1]) * np.diff(t))])


def test_flapping_spectrum_has_table7_harmonics():
    fl = simulate_flight(axis="lon", amplitude=0.0, noise=0.0, ripple=False, duration=4.0)
    t, f = fl["t"], fl["f"]
    meta = fl["meta"]
    fs = 1 / (t[1] - t[0])
    fmean = f.mean()
    # peaks of the reconstructed loads at f, 2f, 3f
    for col in ("X", "Z", "M"):
        y = fl[col] - fl[col].mean()
        spec = np.abs(np.fft.rfft(y * np.hanning(len(y))))
        freq = np.fft.rfftfreq(len(y), 1 / fs)
        band = freq > 5
        peaks = freq[band][signal.find_peaks(spec[band], height=0.05 * spec[band].max())[0]]
        top3 = sorted(peaks[np.argsort(-spec[band][np.searchsorted(freq[band], peaks)])][:3])
        np.testing.assert_allclose(top3, fmean * np.arange(1, 4), atol=0.6)
    # Fourier coefficients: the flapping part of the reconstructed loads (loads minus the
    # cycle-averaged model on the true states), fitted on the phase integrated from the f
    # column (trapezoid), are Table 7's.
    phase = trapezoid_phase(t, f)
    x = meta["states"]
    Fx = np.zeros((len(t), 6))
    p = DELFLY
    Fx[:, 0] = p.Xq * x[:, 0] + p.Xu * x[:, 1] + p.Xw * x[:, 2]
    Fx[:, 2] = p.Zq * x[:, 0] + p.Zu * x[:, 1] + p.Zw * x[:, 2]
    Fx[:, 4] = p.Mq * x[:, 0] + p.Mu * x[:, 1] + p.Mw * x[:, 2]
    H = np.column_stack([g(n * phase) for n in (1, 2, 3) for g in (np.sin, np.cos)])
    sl = slice(10, -10)  # one-sided differences at the very ends
    for i, (col, c) in enumerate((("X", "x"), ("Z", "z"), ("M", "m"))):
        y = fl[col] - meta["trim"][col + "0"] - Fx[:, 2 * i]
        coef = np.linalg.lstsq(H[sl], y[sl], rcond=None)[0]
        want = np.array([TABLE7[f"{ab}{c}{n}"] for n in (1, 2, 3) for ab in "ab"])
        amp = np.max(np.abs(want))
        np.testing.assert_allclose(coef, want, atol=0.01 * amp)


def test_flapping_off_has_no_harmonics():
    fl = simulate_flight(axis="lon", amplitude=0.0, noise=0.0, ripple=False, flapping=False)
    for col in ("q", "u", "w", "X", "Z", "M"):
        assert np.ptp(fl[col]) < 1e-12


def test_drift_keeps_phase_continuous():
    fl = simulate_flight(axis="lon", drift=True, noise=0.0, ripple=False)
    t, f, phase = fl["t"], fl["f"], fl["meta"]["phase"]
    assert f[: len(f) // 10].mean() < 11.8 and f[-len(f) // 10 :].mean() > 12.9
    dphi = np.diff(phase)
    np.testing.assert_allclose(dphi, np.pi * (f[1:] + f[:-1]) * np.diff(t), rtol=1e-4)
    assert np.all(dphi > 0)
    np.testing.assert_allclose(phase, trapezoid_phase(t, f), atol=1e-3)
    # the flapping loads are smooth: no sample-to-sample jump beyond what 3 harmonics allow
    Xf = fl["meta"]["loads_flap"]["X"]
    bound = 2 * np.pi * 3 * 13.3 * np.sum(np.abs([TABLE7[k] for k in TABLE7 if k[1] == "x"]))
    assert np.max(np.abs(np.diff(Xf))) < bound * (t[1] - t[0])
    # naive 2 pi f t would not be: its phase differs from the integrated one by radians
    assert np.max(np.abs(2 * np.pi * f * t - phase)) > 1.0


def test_ripple_is_measured_but_does_not_drive_the_eom():
    a = simulate_flight(axis="lon", noise=0.0, ripple=True)
    b = simulate_flight(axis="lon", noise=0.0, ripple=False)
    for s in STATES:
        np.testing.assert_array_equal(a[s], b[s])
    r = a["de"] - b["de"]
    phase = a["meta"]["phase"]
    H = np.column_stack([np.sin(phase), np.cos(phase), np.sin(2 * phase), np.cos(2 * phase)])
    c = np.linalg.lstsq(H, r, rcond=None)[0]
    amp1, amp2 = np.hypot(c[0], c[1]), np.hypot(c[2], c[3])
    manoeuvre = a["meta"]["truth"]["input"]["amplitude"]
    assert 0.1 * manoeuvre < amp1 < 0.6 * manoeuvre
    assert 0.02 * manoeuvre < amp2 < amp1
    np.testing.assert_allclose(H @ c, r, atol=1e-12)  # nothing but f and 2f


# --------------------------------------------------------------------------- measurement
def test_noise_levels_and_determinism():
    a = simulate_flight(seed=3)
    b = simulate_flight(seed=3)
    c = simulate_flight(seed=4)
    clean = simulate_flight(seed=3, noise=0.0)
    for col in ("q", "u", "theta", "f", "X", "M"):
        np.testing.assert_array_equal(a[col], b[col])
        assert not np.array_equal(a[col], c[col])
    for col, sig in NOISE.items():
        resid = a[col] - clean[col]
        assert 0.85 * sig < resid.std() < 1.15 * sig, col


def test_reconstructed_loads():
    # noise-free: the reconstruction is the true load, up to differentiation error at the
    # input steps and the ends
    fl = simulate_flight(axis="lon", noise=0.0)
    meta = fl["meta"]
    for col in ("X", "Z", "M", "Y", "L", "N"):
        err = (fl[col] - meta["loads_true"][col])[10:-10]
        assert np.median(np.abs(err)) < 2e-3 * np.std(meta["loads_true"][col]), col
    # noisy: noise is realistic (blue: mostly above the body-mode band), the cycle-averaged
    # part stays close to the truth
    fl = simulate_flight(axis="lon", noise=1.0)
    meta = fl["meta"]
    sos = signal.butter(4, 5.0, fs=200.0, output="sos")
    for col in ("X", "Z", "M"):
        true = meta["loads_true"][col]
        lo_err = signal.sosfiltfilt(sos, fl[col] - true)[20:-20]
        assert np.std(lo_err) < 0.12 * np.std(signal.sosfiltfilt(sos, true - true.mean())), col
        assert np.std(fl[col] - true) > 1e-3 * np.std(true)  # carries noise


# --------------------------------------------------------------------------- effects
def test_true_loads_option():
    fl = simulate_flight(axis="lon", noise=0.0, loads="true")
    for col in ("X", "Y", "Z", "L", "M", "N"):
        np.testing.assert_array_equal(fl[col], fl["meta"]["loads_true"][col])
    with pytest.raises(ValueError):
        simulate_flight(loads="measured")


def lowpass(x, fc=5.0):
    sos = signal.butter(4, fc, fs=200.0, output="sos")
    return signal.sosfiltfilt(sos, x, axis=0)


@pytest.mark.parametrize("effect", EFFECTS[1:])
@pytest.mark.parametrize("axis", ["lon", "lat"])
def test_effect_zero_strength_is_none(effect, axis):
    base = simulate_flight(axis=axis, seed=1, input="doublet")
    off = simulate_flight(axis=axis, seed=1, input="doublet", effect=effect, strength=0.0)
    for col in base:
        if col != "meta":
            np.testing.assert_array_equal(base[col], off[col])


@pytest.mark.parametrize("effect", EFFECTS[1:])
@pytest.mark.parametrize("axis", ["lon", "lat"])
def test_effect_changes_flight(effect, axis):
    base = simulate_flight(axis=axis, seed=1, input="doublet", noise=0.0)
    on = simulate_flight(axis=axis, seed=1, input="doublet", noise=0.0, effect=effect)
    xb, xe = base["meta"]["states"], on["meta"]["states"]
    sig = np.array([NOISE[s] for s in STATES])
    if effect == "flap-coupling":
        # the flapping loads change with the motion: their (high-frequency) part differs
        for col in ("X", "Z", "M") if axis == "lon" else ("Y", "N", "X"):
            hb = base[col] - lowpass(base[col])
            he = on[col] - lowpass(on[col])
            assert np.std(he - hb) > 0.05 * np.std(hb), col
    elif effect == "time-offset":  # the motion is the same; the logged control is late
        np.testing.assert_array_equal(xe, xb)
        surf = "de" if axis == "lon" else "dr"
        assert np.max(np.abs(on[surf] - base[surf])) > 0.1 * np.std(base[surf])
    else:
        d = np.sqrt(np.mean(lowpass(xe - xb) ** 2, axis=0)) / sig
        assert d.max() > 3.0, d  # several noise sigmas in some state
    assert on["meta"]["truth"]["effect"] == effect
    assert on["meta"]["truth"]["effect_coefficients"]


def test_lon_lat_coupling_gives_lateral_response_in_lon_flight():
    base = simulate_flight(axis="lon", noise=0.0, flapping=False, ripple=False)
    on = simulate_flight(
        axis="lon", noise=0.0, flapping=False, ripple=False, effect="lon-lat-coupling"
    )
    for s in ("p", "r", "v", "phi"):
        assert np.all(base[s] == 0.0)
        assert np.max(np.abs(on[s])) > 5 * NOISE[s], s


def test_actuator_dynamics_is_a_first_order_lag():
    fl = simulate_flight(
        axis="lon",
        effect="actuator-dynamics",
        strength=1.0,
        noise=0.0,
        input="pulse",
        unit=1.0,
        amplitude=0.1,
    )
    meta = fl["meta"]
    tau = Effect("actuator-dynamics", 1.0).lag_tau()
    assert 0.04 <= tau <= 0.1
    t = fl["t"]
    k0 = meta["first_input"]
    ue = meta["u_eff"][:, 0]
    assert np.all(ue[:k0] == 0.0)
    # after the (one-sample ramp) step the effective deflection follows 1 - exp(-t/tau)
    tt = t[k0 + 5 : k0 + 60] - t[k0]
    want = 0.1 * (1 - np.exp(-(tt + 0.5 * (t[1] - t[0])) / tau))  # ramp centre: t[k0] - dt/2
    np.testing.assert_allclose(ue[k0 + 5 : k0 + 60], want, atol=2e-3)
    # measured de keeps the commanded deflection
    cmd = meta["u_cmd"][:, 0]
    ripple_free = simulate_flight(
        axis="lon",
        effect="actuator-dynamics",
        noise=0.0,
        input="pulse",
        unit=1.0,
        amplitude=0.1,
        ripple=False,
    )
    np.testing.assert_allclose(ripple_free["de"] - meta["trim"]["de0"], cmd, atol=1e-15)


def test_bad_arguments():
    with pytest.raises(ValueError):
        simulate_flight(effect="wind")
    with pytest.raises(ValueError):
        simulate_flight(axis="yaw")
    with pytest.raises(ValueError):
        simulate_flight(substeps=0)
    with pytest.raises(ValueError):
        simulate_flight(noise=-1.0)
