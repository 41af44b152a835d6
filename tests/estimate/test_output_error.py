"""Output-error ML estimation (Eqs. 10-11) on flights simulated by fwid itself."""

import numpy as np
import pytest
import scipy.signal

import fwid
from fwid.estimate import fit
from fwid.models import lateral, longitudinal
from fwid.validate import eigenvalues

SEED = 20240611


def _noise_sigma(ys):
    return 0.02 * np.abs(ys).max(axis=0)  # 2 % of each output's peak


def _white(flight, seed=SEED):
    rng = np.random.default_rng(seed)
    return rng.standard_normal(flight.ys.shape) * _noise_sigma(flight.ys)


def _coloured(flight, seed=SEED):
    rng = np.random.default_rng(seed)
    # first-order 5 Hz low-pass: strongly coloured at 200 Hz (correlation time ~6 samples)
    b, a = scipy.signal.butter(1, 5.0, fs=1.0 / (flight.t[1] - flight.t[0]))
    e = rng.standard_normal((flight.ys.shape[0] + 400, flight.ys.shape[1]))
    e = scipy.signal.lfilter(b, a, e, axis=0)[400:]  # drop the filter's start-up
    return e / e.std(axis=0) * _noise_sigma(flight.ys)


def _aero(names, biases):
    return np.array([k not in biases for k in names])


# -- fits shared by the tests below (one compilation per model / noise structure) ----------
@pytest.fixture(scope="module")
def lon_clean(lon_flight):
    return fit(longitudinal(), lon_flight.experiment())


@pytest.fixture(scope="module")
def lon_white(lon_flight):
    return fit(longitudinal(), lon_flight.experiment(lon_flight.ys + _white(lon_flight)))


@pytest.fixture(scope="module")
def lon_coloured(lon_flight):
    return fit(longitudinal(), lon_flight.experiment(lon_flight.ys + _coloured(lon_flight)))


@pytest.fixture(scope="module")
def lat_clean_diag(lat_flight):
    return fit(lateral(), lat_flight.experiment(), noise="diagonal")


@pytest.fixture(scope="module")
def lat_white_diag(lat_flight):
    return fit(lateral(), lat_flight.experiment(lat_flight.ys + _white(lat_flight)),
               noise="diagonal")


# -- the simulated truth -----------------------------------------------------------------
def test_true_models_are_stable_and_differ_from_nominal(lon_flight, lat_flight):
    for fl in (lon_flight, lat_flight):
        ev = eigenvalues(fl.model, fl.consts)
        assert np.all(ev.real < -0.1), ev
        nominal = np.asarray((longitudinal() if fl.model.name == "lon" else lateral()).theta())
        assert np.all(fl.theta != nominal)  # the start must do real work
        # the manoeuvre moves every output well above numerical noise
        assert np.all(np.ptp(fl.ys, axis=0) > 1e-2)


# -- noise-free: exact recovery ------------------------------------------------------------
def _assert_recovered(res, flight, biases):
    assert res.names == flight.names
    theta = np.asarray(res.theta)
    aero = _aero(res.names, biases)
    np.testing.assert_allclose(theta[aero], flight.theta[aero], rtol=1e-6, atol=0)
    np.testing.assert_allclose(theta[~aero], flight.theta[~aero], rtol=0, atol=1e-9)
    assert bool(res.converged)
    # the returned model carries the estimates
    for k, v in zip(res.names, theta):
        assert float(res.model.params[k]) == v


def test_lon_noise_free_recovers_truth(lon_clean, lon_flight):
    _assert_recovered(lon_clean, lon_flight, lon_flight.model.local)


@pytest.mark.slow
def test_lat_noise_free_recovers_truth(lat_clean_diag, lat_flight):
    _assert_recovered(lat_clean_diag, lat_flight, lat_flight.model.local)


def test_start_from_given_model_or_model_values(lon_clean, lon_flight):
    exp = lon_flight.experiment()
    true = {k: float(v) for k, v in lon_flight.model.params.items()}
    near = longitudinal(true).with_params(
        {k: 1.15 * v for k, v in true.items() if k not in lon_flight.model.local})
    for start in (near, "model"):
        model = near if start == "model" else longitudinal()
        res = fit(model, exp, start=start)
        np.testing.assert_allclose(np.asarray(res.start), np.asarray(near.theta()))
        np.testing.assert_allclose(np.asarray(res.theta), lon_flight.theta, rtol=1e-6,
                                   atol=1e-9)
    with pytest.raises(ValueError, match="start"):
        fit(longitudinal(), exp, start="zeros")


# -- white measurement noise ------------------------------------------------------------
def test_white_noise_estimates_within_4_std(lon_white, lon_flight):
    err = np.asarray(lon_white.theta) - lon_flight.theta
    assert np.all(np.abs(err) < 4 * np.asarray(lon_white.std)), err / lon_white.std
    assert np.all(np.abs(err) < 4 * np.asarray(lon_white.std_cr)), err / lon_white.std_cr
    # ... and the noise actually moved them (the test is not vacuous)
    assert np.all(err != 0)
    assert bool(lon_white.converged)


def test_white_noise_R_estimates_noise_covariance(lon_white, lon_flight):
    R = np.asarray(lon_white.R)
    sig2 = _noise_sigma(lon_flight.ys) ** 2
    np.testing.assert_allclose(R, R.T, rtol=0, atol=1e-15 * np.abs(R).max())
    # Eq. (11) with 901 samples: each variance within ~5 % (1 sigma) of the truth
    np.testing.assert_allclose(np.diag(R), sig2, rtol=0.2)
    corr = R / np.sqrt(np.outer(np.diag(R), np.diag(R)))
    assert np.all(np.abs(corr[~np.eye(4, dtype=bool)]) < 0.15), corr


def test_white_noise_std_close_to_cramer_rao(lon_white):
    """For white residuals the coloured-residual correction must be about neutral."""
    ratio = np.asarray(lon_white.std / lon_white.std_cr)
    assert np.all((ratio > 0.7) & (ratio < 1.5)), dict(zip(lon_white.names, ratio.round(2)))
    assert 0.8 < np.median(ratio) < 1.25, ratio


# -- coloured (low-pass filtered) measurement noise ------------------------------------------
def test_coloured_noise_std_exceeds_cramer_rao(lon_coloured):
    ratio = np.asarray(lon_coloured.std / lon_coloured.std_cr)
    assert np.all(ratio > 1.3), dict(zip(lon_coloured.names, ratio.round(2)))
    assert np.median(ratio) > 2.0, ratio
    assert np.all(np.asarray(lon_coloured.std_cr) > 0)
    assert bool(lon_coloured.converged)


def test_coloured_vs_white_cramer_rao_is_overconfident(lon_coloured, lon_flight):
    # with coloured noise the plain Cramer-Rao bounds are far too small ...
    z = (np.asarray(lon_coloured.theta) - lon_flight.theta) / np.asarray(lon_coloured.std_cr)
    assert np.max(np.abs(z)) > 4, z
    # ... the corrected ones are of the right size
    zc = (np.asarray(lon_coloured.theta) - lon_flight.theta) / np.asarray(lon_coloured.std)
    assert np.max(np.abs(zc)) < 5, zc


# -- noise covariance structure -----------------------------------------------------------
@pytest.mark.slow
def test_diagonal_noise_gives_diagonal_R(lat_white_diag, lat_flight):
    R = np.asarray(lat_white_diag.R)
    assert np.all(R[~np.eye(4, dtype=bool)] == 0.0), R
    np.testing.assert_allclose(np.diag(R), _noise_sigma(lat_flight.ys) ** 2, rtol=0.2)
    err = np.asarray(lat_white_diag.theta) - lat_flight.theta
    assert np.all(np.abs(err) < 4 * np.asarray(lat_white_diag.std_cr)), err / lat_white_diag.std_cr


def test_full_noise_R_is_not_diagonal(lon_white):
    R = np.asarray(lon_white.R)
    assert np.any(R[~np.eye(4, dtype=bool)] != 0.0)


# -- cost ------------------------------------------------------------------------------
def test_cost_history_decreases_and_matches_eq10(lon_white):
    hist = np.asarray(lon_white.cost_history)
    k = int(lon_white.passes)
    assert k >= 2
    assert np.all(np.isfinite(hist[:k])) and np.all(np.isnan(hist[k:]))
    assert np.all(np.diff(hist[:k]) <= 1e-9 * np.abs(hist[:k-1])), hist
    assert hist[0] > hist[k - 1]
    assert float(lon_white.cost) == hist[k - 1]
    # Eq. (10) at the Eq. (11) R: N ny/2 + N/2 ln det R + N ny/2 ln 2 pi
    R = np.asarray(lon_white.R)
    n, ny = 901, 4
    expected = 0.5 * n * ny + 0.5 * n * np.linalg.slogdet(R)[1] + 0.5 * n * ny * np.log(2 * np.pi)
    assert float(lon_white.cost) == pytest.approx(expected, rel=1e-12)


def test_table_layout(lon_white):
    tab = lon_white.table()
    assert list(tab) == list(lon_white.names)
    i = lon_white.names.index("Mq")
    row = tab["Mq"]
    assert row["value"] == float(lon_white.theta[i])
    assert row["std"] == float(lon_white.std[i])
    assert row["std_cr"] == float(lon_white.std_cr[i])
    assert row["rel_std_pct"] == pytest.approx(100 * abs(row["std"] / row["value"]))
    corr = np.asarray(lon_white.corr)
    np.testing.assert_allclose(np.diag(corr), 1.0, rtol=1e-12)


# -- errors -----------------------------------------------------------------------------
def test_input_that_never_moves_raises(lon_flight):
    exp = lon_flight.experiment(u=np.full(lon_flight.t.shape, 0.01))
    with pytest.raises(fwid.ExcitationError, match="'de'") as info:
        fit(longitudinal(), exp, names=["still_flight"])
    assert "still_flight" in str(info.value)
    assert isinstance(info.value, fwid.InputError)


def _named_parameters(message):
    tail = message.split("parameter", 1)[1].split("(", 1)[0]
    return {w.strip(" ,s") for w in tail.split(",") if w.strip(" ,s")}


def test_parameter_without_influence_raises(lon_flight):
    # Infinite pitch inertia: Mq, Mu, Mw, Mde all multiply 1/Iy = 0 (no influence at all).
    consts = dict(lon_flight.consts, Iy=np.inf)
    exp = lon_flight.experiment(consts=consts)
    with pytest.raises(fwid.ExcitationError) as info:
        fit(longitudinal(), exp, names=["flight_B"])
    msg = str(info.value)
    assert "flight_B" in msg
    named = _named_parameters(msg)
    assert named == {"Mq", "Mu", "Mw", "Mde"}, msg


def test_blow_up_start_recovers_or_raises_diverged(lon_flight):
    bad = longitudinal().with_params(Mq=1.0)  # Mq/Iy = +1.7e4 1/s: the simulation overflows
    exp = lon_flight.experiment()
    try:
        res = fit(bad, exp, start="model", names=["flight_A"])
    except fwid.FitDivergedError as e:
        assert "flight_A" in str(e)
    else:
        assert bool(res.converged)
        np.testing.assert_allclose(np.asarray(res.theta), lon_flight.theta, rtol=1e-6,
                                   atol=1e-9)


def test_fit_each_identical_to_fitting_each_flight_alone(lon_flight):
    """The vmapped estimator freezes a flight once it has converged: the batched estimates
    are those of fwid.fit on each flight alone (1e-10 relative, the uncertainties too)."""
    exps = [lon_flight.experiment(lon_flight.ys + _white(lon_flight, seed=s)) for s in (1, 2, 3)]
    batched = fwid.fit_each(longitudinal(), exps)
    for e, b in zip(exps, batched):
        a = fit(longitudinal(), e)
        np.testing.assert_allclose(np.asarray(b.theta), np.asarray(a.theta), rtol=1e-10, atol=0)
        np.testing.assert_allclose(np.asarray(b.std), np.asarray(a.std), rtol=1e-10, atol=0)
        assert int(b.steps) == int(a.steps) and bool(b.converged)


def test_batched_normal_equations_are_each_fits_own():
    """Under `vmap` (fit_each) the normal equations are formed fit by fit: each fit's H and
    g are bit for bit those of the fit alone, and equal the textbook sums."""
    import jax
    import jax.numpy as jnp

    from fwid.estimate._gauss_newton import normal_equations

    rng = np.random.default_rng(0)
    v = jnp.asarray(rng.standard_normal((5, 300, 4)))
    J = jnp.asarray(rng.standard_normal((5, 300, 4, 7)) * np.logspace(-2, 2, 7))
    Rinv = jnp.asarray(np.linalg.inv(np.cov(rng.standard_normal((4, 50))) + np.eye(4)))
    H, g = jax.jit(jax.vmap(normal_equations, in_axes=(0, 0, None)))(v, J, Rinv)
    assert H.shape == (5, 7, 7) and g.shape == (5, 7)
    for i in range(5):
        Hi, gi = jax.jit(normal_equations)(v[i], J[i], Rinv)
        np.testing.assert_array_equal(np.asarray(H[i]), np.asarray(Hi))
        np.testing.assert_array_equal(np.asarray(g[i]), np.asarray(gi))
        Ji, vi = np.asarray(J[i]), np.asarray(v[i])
        ref_H = sum(Ji[k].T @ np.asarray(Rinv) @ Ji[k] for k in range(300))
        ref_g = sum(Ji[k].T @ np.asarray(Rinv) @ vi[k] for k in range(300))
        np.testing.assert_allclose(np.asarray(Hi), ref_H, rtol=1e-12)
        np.testing.assert_allclose(np.asarray(gi), ref_g, rtol=1e-10,
                                   atol=1e-12 * np.abs(ref_g).max())


def test_a_joint_fits_jacobian_equals_jacfwd_through_the_simulation():
    """Each flight's sensitivities are integrated for the global parameters and its own
    local ones only; the full Jacobian (zero for the other flights' locals) equals
    `jax.jacfwd` of the residuals of the whole batch."""
    import jax
    import jax.numpy as jnp

    from fwid.estimate._output_error import raw_residuals, residuals_with_jacobian
    from fwid.estimate._problem import free_layout, merge_batch
    from fwid.models import TABLE1, longitudinal
    from fwid.simulation import Experiment
    from fwid.simulation._experiment import stack_experiments

    from .conftest import LON_CONSTS

    model = longitudinal(dict(TABLE1, bq=0.01, bu=-0.003, bw=0.002, btheta=0.001))
    rng = np.random.default_rng(3)
    exps = []
    for k in range(3):
        t = np.arange(0, 2 + 0.5 * k, 0.01)
        u = (0.05 * np.sin(2 * np.pi * (0.7 + 0.3 * k) * t))[:, None]
        exps.append(Experiment(t, u, 0.01 * rng.standard_normal((len(t), 4)),
                               x0=0.01 * rng.standard_normal(4), consts=LON_CONSTS))
    batch = stack_experiments(exps)
    B = len(exps)
    glob, loc, names = free_layout(model, B)
    assert loc, "the model needs local (bias) parameters for a joint fit"
    values = [float(model.params[k]) for k in glob] + [
        float(model.params[k]) + 0.01 * b for k in loc for b in range(B)]
    theta = jnp.asarray(values) * (1.0 + 0.05 * rng.standard_normal(len(names)))
    r, J = residuals_with_jacobian(model, batch, B)(theta)
    r_ref = raw_residuals(model, merge_batch(model, theta, B), batch)
    J_ref = jax.jacfwd(lambda th: raw_residuals(model, merge_batch(model, th, B), batch))(theta)
    np.testing.assert_allclose(r, r_ref, atol=1e-12)
    np.testing.assert_allclose(J, J_ref, rtol=1e-8, atol=1e-10)
    # flight 0's row is zero for flight 1's bias terms, and not for its own
    own1 = [names.index(f"{k}@1") for k in loc]
    own0 = [names.index(f"{k}@0") for k in loc]
    assert np.all(np.asarray(J)[0][..., own1] == 0.0)
    assert np.any(np.asarray(J)[0][..., own0] != 0.0)
