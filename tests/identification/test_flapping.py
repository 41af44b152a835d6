"""The flapping and combined pipelines (Sections V-VI) and `fwid identify --model flap|combined`.

The flights are simulated here, independently of fwid (scipy's DOP853 on Eq. 7 with the
Table 1 aerodynamics plus the Table 7 flapping forces, Eqs. 13-15), started on the periodic
flapping orbit and at different points of the stroke; the loads are the true aerodynamic
forces `F_TA(x) + F_TV(phase)` plus noise, as "reconstructed from the motion".
"""

import contextlib
import io
import json

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fwid
from fwid import FitResult, Identification
from fwid.identification import evaluate, identify_combined, identify_flapping_model, steady_vs_manoeuvre
from fwid.report import flapping_report
from fwid.simulation import averaged
from fwid.cli import main
from fwid.data import Flight
from fwid.estimate import refit_local_affine
from fwid.models import TABLE1, longitudinal
from fwid.models._fourier import fourier_param_names, shift_phase

from ..paper import TABLE7

VEHICLE = dict(mass=0.0205, Ix=8e-5, Iy=6e-5, Iz=3e-5, Ixz=1e-6, g=9.81)
TRIM = dict(u0=0.3, w0=0.6, theta0=1.2)
SIGMA = dict(q=0.01, u=0.001, w=0.001, theta=5e-4, X=0.005, Z=0.005, M=2.5e-4, de=0.002)
RATE = 200.0
PHASE0 = {"est.csv": 0.4, "val.csv": 2.0}


def _series(phase, o):
    return sum(TABLE7[f"a{o}{n}"] * np.sin(n * phase) + TABLE7[f"b{o}{n}"] * np.cos(n * phase)
               for n in (1, 2, 3))


def _doublet(t, t0, half=0.4, amp=0.1, rise=0.03):
    s = lambda a: 0.5 * (1 + np.tanh((t - a) / rise))  # noqa: E731
    return amp * (s(t0) - 2 * s(t0 + half) + s(t0 + 2 * half))


def simulate_delfly(*, phase0, seed, t_input=1.5, duration=4.5, f=12.5):
    """Columns of one longitudinal flight (absolute values) and its first-input index."""
    p, m, Iy, g = TABLE1, VEHICLE["mass"], VEHICLE["Iy"], VEHICLE["g"]
    u0, w0, th0 = TRIM["u0"], TRIM["w0"], TRIM["theta0"]

    def loads(x, t):
        q, u, w, _ = x
        de = _doublet(t, t_input)
        ph = phase0 + 2 * np.pi * f * t
        return (p["Xq"] * q + p["Xu"] * u + p["Xw"] * w + p["Xde"] * de + _series(ph, "x"),
                p["Zq"] * q + p["Zu"] * u + p["Zw"] * w + p["Zde"] * de + _series(ph, "z"),
                p["Mq"] * q + p["Mu"] * u + p["Mw"] * w + p["Mde"] * de + _series(ph, "m"))

    def rhs(t, x):
        X, Z, M = loads(x, t)
        return [M / Iy, X / m - w0 * x[0] - g * np.cos(th0) * x[3],
                Z / m + u0 * x[0] - g * np.sin(th0) * x[3], x[0]]

    n = int(round(duration * RATE)) + 1
    t = np.arange(n) / RATE
    # 3 s of run-up onto the periodic flapping orbit (the body modes decay well before t = 0)
    x = solve_ivp(rhs, (-3.0, duration), np.zeros(4), t_eval=t, method="DOP853", rtol=1e-10,
                  atol=1e-12).y
    X, Z, M = loads(x, t)
    rng = np.random.default_rng(seed)
    cols = {"t": t, "q": x[0], "u": u0 + x[1], "w": w0 + x[2], "theta": th0 + x[3],
            "de": 0.05 + _doublet(t, t_input) + 0.01 * np.sin(phase0 + 2 * np.pi * f * t),
            "f": np.full(n, f),
            "X": X + m * g * np.sin(th0), "Z": Z - m * g * np.cos(th0), "M": M}
    for k, s in SIGMA.items():
        cols[k] = cols[k] + s * rng.standard_normal(n)
    return cols, int(np.searchsorted(t, t_input - 0.1))


def write_flight(folder, name, cols, first):
    keys = list(cols)
    np.savetxt(folder / name, np.stack([cols[k] for k in keys], -1), delimiter=",",
               header=",".join(keys), comments="", fmt="%.17g")
    m, g, th0 = VEHICLE["mass"], VEHICLE["g"], TRIM["theta0"]
    trim = dict(TRIM, q0=0.0, de0=0.05, X0=m * g * np.sin(th0), Z0=-m * g * np.cos(th0), M0=0.0)
    (folder / name).with_suffix(".json").write_text(
        json.dumps({"trim": trim, "first_input": first}))
    return folder / name


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    folder = tmp_path_factory.mktemp("flap_flights")
    (folder / "vehicle.json").write_text(json.dumps(VEHICLE))
    est = write_flight(folder, "est.csv", *simulate_delfly(phase0=PHASE0["est.csv"], seed=3))
    val = write_flight(folder, "val.csv", *simulate_delfly(phase0=PHASE0["val.csv"], seed=4,
                                                           t_input=2.0))
    return folder, est, val


def run_cli(args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(args)
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def flap_run(data, tmp_path_factory):
    _, est, val = data
    out = tmp_path_factory.mktemp("flap_out")
    rc, text, err = run_cli(["identify", str(est), "--validate", str(val), "--model", "flap",
                             "--out", str(out), "--quiet"])
    assert rc == 0, err
    return out, text, json.loads((out / "report.json").read_text())


# -- the combined model (Section VI) ---------------------------------------------------------
# Section IV's estimator (the cycle-averaged fit) is tested on its own elsewhere and takes
# most of a minute to compile; here the cycle-averaged model is given (the truth, Table 1),
# its bias terms re-estimated per flight, and everything of Sections V-VI is identified.


@pytest.fixture(scope="module")
def combined_ident(data):
    _, est, val = data
    return identify_combined(fwid.load_flights(est), validate=fwid.load_flights(val),
                             cycle=longitudinal(TABLE1))


def test_combined_fourier_coefficients_within_uncertainty(combined_ident):
    """The Fourier part comes back within 3 standard deviations of Table 7 (in the phase
    frame of the estimation flight, which starts 0.4 rad into the stroke)."""
    r = combined_ident.flapping.fit
    truth = shift_phase(TABLE7, PHASE0["est.csv"])
    z = np.array([(float(r.theta[i]) - truth[k]) / float(r.std[i])
                  for i, k in enumerate(r.names)])
    print("Fourier coefficient error / std:", np.round(z, 2))
    assert np.all(np.abs(z) < 3.0)


def test_combined_flapping_peaks_match(combined_ident):
    """The first three flapping peaks of every state and force of the combined simulation
    match the data's within 5 % (those that stand clear of the sensor noise: more than 60
    standard errors `sigma sqrt(2 / N)` of the amplitude estimate, so that the noise alone
    moves them by less than 5 % / 3; that leaves out theta's third harmonic)."""
    n = 4.5 * RATE + 1 - 2 * 0.2 * RATE
    checked, worst = 0, 0.0
    for flight, signals in combined_ident.peaks.items():
        for k, d in signals.items():
            for i, (a, b) in enumerate(zip(d["measured"], d["model"])):
                if a > 60 * SIGMA[k] * np.sqrt(2 / n):
                    print(f"{flight} {k} harmonic {i + 1}: model / measured = {b / a:.4f}")
                    assert abs(b / a - 1) < 0.05, (flight, k, i + 1, b / a)
                    checked += 1
                    worst = max(worst, abs(b / a - 1))
    print(f"{checked} peaks checked, worst {100 * worst:.2f} %")
    assert checked >= 40  # of the 2 flights x 7 signals x 3 harmonics


def test_combined_validation_and_parts(combined_ident):
    ident = combined_ident
    d = ident.flapping.phase_offsets["val.csv"]
    expected = PHASE0["val.csv"] - PHASE0["est.csv"]
    assert abs((d - expected + np.pi) % (2 * np.pi) - np.pi) < 0.02
    assert ident.flapping.phase_offsets["est.csv"] == 0.0
    assert ident.model.inputs == ("de", "phase")
    val = ident.validation[0]
    assert val.metrics["q"]["r2"] > 0.99 and val.metrics["M"]["r2"] > 0.95
    # the biases of the given model were re-estimated per flight (the truth has none)
    for k in ("bq", "bu", "bw", "btheta"):
        assert abs(val.local_params[k]) < 0.02
    parts = ident.parts["est.csv"]
    ff = ident.estimation[0]
    np.testing.assert_allclose(parts["TA"]["M"] + parts["TV"]["M"], ff.forces_simulated["M"],
                               rtol=1e-10, atol=1e-15)
    # the eigenvalues are those of Eq. (7) with Table 1 (the Fourier part adds no dynamics)
    c = ident.consts
    m, Iy, g, u0, w0, th0 = (c[k] for k in ("mass", "Iy", "g", "u0", "w0", "theta0"))
    p = TABLE1
    A = np.array([
        [p["Mq"] / Iy, p["Mu"] / Iy, p["Mw"] / Iy, 0.0],
        [p["Xq"] / m - w0, p["Xu"] / m, p["Xw"] / m, -g * np.cos(th0)],
        [p["Zq"] / m + u0, p["Zu"] / m, p["Zw"] / m, -g * np.sin(th0)],
        [1.0, 0.0, 0.0, 0.0],
    ])
    np.testing.assert_allclose(np.sort_complex(ident.eigenvalues),
                               np.sort_complex(np.linalg.eigvals(A)), rtol=1e-10)


def test_bias_refit_is_the_ml_estimate(data):
    """The bias terms of a validation flight by linear least squares (the cycle-averaged
    model is affine in them) equal what the Gauss-Newton estimator finds."""
    _, _, val = data
    model = longitudinal(dict(TABLE1, bq=0.01, bu=-0.003))
    exp = averaged(fwid.load_flights(val)[0], model, 5.0)
    lin = refit_local_affine(model, exp)
    model_free = model.with_free(model.local)
    # the estimator's fixed point: the gradient of the ML cost at the linear solution is ~0
    y = np.asarray(fwid.simulate(model.with_params(lin), exp)[1])
    v = np.asarray(exp.z) - y
    R = v.T @ v / v.shape[0]
    step = 1e-6
    grads = []
    for k in model_free.free:
        yk = np.asarray(fwid.simulate(model.with_params({**lin, k: lin[k] + step}), exp)[1])
        S = (yk - y) / step
        grads.append(np.sum(v @ np.linalg.inv(R) * S))
    scale = np.sqrt(np.sum(v @ np.linalg.inv(R) * v))
    assert np.max(np.abs(grads)) < 1e-6 * scale * 1e3
    assert set(lin) == {"bq", "bu", "bw", "btheta"}


def _canned_identify(flights, axis, *, joint=False, cutoff=5.0, progress=False):
    """Section IV without the estimator: the true model, as if identified."""
    model = longitudinal(TABLE1)
    exps = [averaged(f, model, cutoff) for f in flights]
    theta = jnp.stack([model.params[k] for k in model.free])
    p = theta.shape[0]
    fit = FitResult(model=model, names=tuple(model.free), theta=theta,
                    std=0.01 * jnp.abs(theta) + 1e-9, std_cr=0.01 * jnp.abs(theta) + 1e-9,
                    cov=jnp.eye(p), corr=jnp.eye(p), R=jnp.eye(4), cost=jnp.asarray(0.0),
                    cost_history=jnp.zeros(1), passes=jnp.asarray(1), steps=jnp.asarray(1),
                    converged=jnp.asarray(True), start=theta)
    est = [evaluate(model, e, f.name, refit_local=False) for e, f in zip(exps, flights)]
    return Identification(model=model, flights=[f.name for f in flights], fits=[fit],
                          estimation=est, consts={k: float(v) for k, v in exps[0].consts.items()})


def test_combined_cli(data, tmp_path, monkeypatch):
    """`fwid identify --model combined`: the report (docs/reference/formats.md) and Figures 12,
    15-17 (the cycle-averaged estimator stubbed out, see above)."""
    from fwid.identification import _combined as pipeline

    monkeypatch.setattr(pipeline, "identify", _canned_identify)
    _, est, val = data
    rc, text, err = run_cli(["identify", str(est), "--validate", str(val), "--model",
                             "combined", "--out", str(tmp_path), "--quiet"])
    assert rc == 0, err
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["model"] == "combined" and report["flights"] == ["est.csv"]
    names = set(TABLE1) | set(fourier_param_names(("X", "Z", "M")))
    assert names <= set(report["parameters"])
    for p in report["parameters"].values():
        assert {"value", "std"} <= set(p)
    assert len(report["eigenvalues"]) == 4 and all(len(e) == 2 for e in report["eigenvalues"])
    for part in ("estimation", "validation"):
        assert set(report["metrics"][part]) == {"q", "u", "w", "theta", "X", "Z", "M"}
        for m in report["metrics"][part].values():
            assert {"corr", "r2", "rms", "rms_pct"} <= set(m)
    assert report["metrics"]["validation"]["q"]["r2"] > 0.95
    assert abs(report["phase_offsets"]["val.csv"] - 1.6) < 0.02
    assert set(report["peaks"]) == {"est.csv", "val.csv"}
    for fig in ("combined_fit_est.png", "combined_validation_val.png", "superposition_est.png",
                "flap_fit_est.png", "poles.png"):
        assert (tmp_path / fig).stat().st_size > 10_000, fig
    assert "Table 7" in text and "validation" in text and "first flapping peaks" in text


# -- fwid identify --model flap (Section V) --------------------------------------------------


def test_flap_report_and_figures(flap_run):
    out, text, report = flap_run
    assert report["model"] == "flap" and report["eigenvalues"] == []
    assert list(report["parameters"]) == list(fourier_param_names(("X", "Z", "M")))
    for part in ("estimation", "validation"):
        assert set(report["metrics"][part]) == {"X", "Z", "M"}
        for m in report["metrics"][part].values():
            assert m["rms_pct"] < 6.0  # Table 8 reports 10-25 % on real data
    assert abs(report["phase_offsets"]["val.csv"] - 1.6) < 0.02
    svm = report["steady_vs_manoeuvre"]["est.csv"]
    assert set(svm["steady"]) == {"X", "Z", "M"}
    for fig in ("flap_fit_est.png", "flap_validation_val.png", "steady_vs_manoeuvre_est.png"):
        assert (out / fig).stat().st_size > 10_000, fig
    assert "Table 7" in text and "Table 8" in text and "steady flight vs manoeuvre" in text


def test_flap_only_model_carries_the_state_driven_part(flap_run, combined_ident):
    """Fitted to the flapping part of the forces alone (the paper's Section V), the series
    also takes in the cycle-averaged forces of the flapping motion (e.g. Mq q at 12.5 Hz),
    so it differs from Table 7; the combined pipeline takes those off first."""
    flap = flap_run[2]["parameters"]
    r = combined_ident.flapping.fit
    truth = shift_phase(TABLE7, PHASE0["est.csv"])
    zf = max(abs((flap[k]["value"] - truth[k]) / flap[k]["std"]) for k in truth)
    zc = max(abs((float(r.theta[i]) - truth[k]) / float(r.std[i])) for i, k in enumerate(r.names))
    print(f"largest |error| / std: flapping part alone {zf:.1f}, combined {zc:.1f}")
    assert zf > 5 > zc


def test_cli_missing_frequency_column(tmp_path, data):
    folder, est, _ = data
    text = est.read_text().splitlines()
    header = text[0].split(",")
    j = header.index("f")
    rows = [",".join(c for i, c in enumerate(line.split(",")) if i != j) for line in text]
    (tmp_path / "vehicle.json").write_text((folder / "vehicle.json").read_text())
    (tmp_path / "nof.csv").write_text("\n".join(rows) + "\n")
    rc, _, err = run_cli(["identify", str(tmp_path / "nof.csv"), "--model", "flap", "--quiet"])
    assert rc == 2
    assert "'f'" in err and "nof.csv" in err


def test_several_flights_are_phase_aligned(data):
    _, est, val = data
    flights = fwid.load_flights(est, val)
    joint = identify_flapping_model(flights, joint=True)
    alone = identify_flapping_model(flights[:1])
    assert abs(joint.phase_offsets["val.csv"] - 1.6) < 0.02
    assert len(joint.fits) == 1 and joint.joint
    # two aligned flights: the same coefficients, known better
    for i, k in enumerate(joint.fit.names):
        assert abs(float(joint.fit.theta[i]) - float(alone.fit.theta[i])) < 4 * float(
            alone.fit.std[i])
    assert np.all(np.asarray(joint.fit.std) < np.asarray(alone.fit.std))
    per = identify_flapping_model(flights)
    assert len(per.fits) == 2
    report = flapping_report(per)
    assert len(report["per_flight"]) == 2 and report["parameters"]["bx1"]["std"] > 0


# -- Figures 12 and 14: steady flight vs manoeuvre -------------------------------------------


def _eq12_flight(modulate: bool, seed=0):
    n, dt, k = 1201, 0.005, 500
    t = np.arange(n) * dt
    phase = 0.3 + 2 * np.pi * 12.5 * t
    F = np.stack([_series(phase, o) for o in "xzm"], -1)
    de = np.where(t > k * dt, 0.1 * np.sin(2 * np.pi * 1.2 * (t - k * dt)), 0.0)
    if modulate:  # the manoeuvre changes the wing beat: amplitude follows de, plus a wobble
        wobble = np.sin(2 * np.pi * 17.0 * t + 0.5 * np.sin(2 * np.pi * 3 * t))
        F = F * (1 + 4 * de[:, None]) + (np.abs(de) > 0)[:, None] * 0.2 * np.abs(F).max(0) * \
            wobble[:, None]
    rng = np.random.default_rng(seed)
    F = F + np.array([0.005, 0.005, 2.5e-4]) * rng.standard_normal(F.shape)
    cols = {"X": F[:, 0], "Z": F[:, 1], "M": F[:, 2], "f": np.full(n, 12.5), "de": de}
    return Flight(t=jnp.asarray(t), columns={c: jnp.asarray(v) for c, v in cols.items()},
                  trim={}, vehicle=None, name="svm.csv", first_input=k)


def test_steady_vs_manoeuvre():
    clean = steady_vs_manoeuvre(_eq12_flight(False))
    coupled = steady_vs_manoeuvre(_eq12_flight(True))
    for o in ("X", "Z", "M"):
        s, m = clean.summary["steady"][o], clean.summary["manoeuvre"][o]
        # time-scale separation holds: both parts are equally periodic (noise only)
        assert 0.8 < m["rms"] / s["rms"] < 1.25
        s, m = coupled.summary["steady"][o], coupled.summary["manoeuvre"][o]
        print(o, "steady", s, "manoeuvre", m)
        assert m["rms_pct"] > 2 * s["rms_pct"]
        assert m["nonharmonic_pct"] > 3 * s["nonharmonic_pct"]
    assert clean.split == 500 and clean.steady.t[-1] < clean.manoeuvre.t[0]
    with pytest.raises(fwid.InputError, match="flapping cycles"):
        steady_vs_manoeuvre(_eq12_flight(False), split=60)
