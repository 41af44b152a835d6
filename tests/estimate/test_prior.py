"""A Gaussian prior on parameters in the output-error fit (maximum a posteriori)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.estimate._gauss_newton import NoiseModel
from fwid.estimate._prior import PriorBounds, prior_bounds
from fwid.simulation import simulate
from fwid.simulation._experiment import with_measured_x0


def test_prior_as_strong_as_the_data_halves_the_variance(short_period):
    """A prior on Mq centred on the ML estimate with std equal to its Cramer-Rao std s: the
    estimates stay, and (Sherman-Morrison: `[(M + e e^T/s^2)^-1]_ii = c - c^2/(s^2 + c)` with
    `c = [M^-1]_ii = s^2`) Mq's variance halves exactly, whatever its correlations."""
    sp = short_period
    m, s = sp.at(sp.plain, "Mq"), sp.std_cr(sp.plain, "Mq")
    r = fwid.fit(sp.model, sp.exps[0], prior={"Mq": (m, s)})
    np.testing.assert_allclose(np.asarray(r.theta), np.asarray(sp.plain.theta), rtol=1e-9,
                               atol=1e-12)
    np.testing.assert_allclose(sp.std_cr(r, "Mq") ** 2, s**2 / 2, rtol=1e-6)
    # the others shrink less (only through their correlation with Mq), none grows
    others = [i for i, k in enumerate(r.names) if k != "Mq"]
    ratio = np.asarray(r.std_cr)[others] / np.asarray(sp.plain.std_cr)[others]
    assert np.all(ratio <= 1 + 1e-9) and np.all(ratio > 1 / np.sqrt(2))
    assert r.prior_table() == {"Mq": {"mean": m, "std": pytest.approx(s, rel=1e-12)}}


def test_prior_pulls_the_estimate_halfway_as_the_algebra_says(short_period):
    """With std equal to the data's s, a prior mean 2 s away moves the estimate by s (the
    precision-weighted mean; exact for a linear-in-theta model, near for this one)."""
    sp = short_period
    m, s = sp.at(sp.plain, "Mq"), sp.std_cr(sp.plain, "Mq")
    r = fwid.fit(sp.model, sp.exps[0], prior={"Mq": {"mean": m + 2 * s, "std": s}})
    assert sp.at(r, "Mq") - m == pytest.approx(s, rel=0.05)
    assert bool(r.converged)


def test_prior_with_huge_std_changes_nothing(short_period):
    sp = short_period
    r = fwid.fit(sp.model, sp.exps[0], prior={"Mq": (0.0, 1e6), "Ma": (3.0, 1e7)})
    np.testing.assert_allclose(np.asarray(r.theta), np.asarray(sp.plain.theta), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(r.std_cr), np.asarray(sp.plain.std_cr), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(r.std), np.asarray(sp.plain.std), rtol=1e-9)


def test_very_strong_prior_pins_the_parameter(short_period):
    """A prior of std 1e-9 on Mq at -2.3 holds it there: the others are those of the fit
    with Mq fixed at -2.3, and Mq's std is the prior's."""
    sp = short_period
    r = fwid.fit(sp.model, sp.exps[0], prior={"Mq": (-2.3, 1e-9)})
    assert sp.at(r, "Mq") == pytest.approx(-2.3, abs=1e-8)
    for k in sp.held_mq.names:
        assert sp.at(r, k) == pytest.approx(sp.at(sp.held_mq, k), rel=1e-5, abs=1e-9)
        assert sp.std_cr(r, k) == pytest.approx(sp.std_cr(sp.held_mq, k), rel=1e-4)
    assert sp.std_cr(r, "Mq") == pytest.approx(1e-9, rel=1e-3)


def test_prior_from_a_fit_and_a_report(short_period):
    sp = short_period
    p = fwid.prior_from(sp.plain, scale=2.0)
    assert list(p) == list(sp.plain.names)
    for i, k in enumerate(sp.plain.names):
        assert p[k] == (float(sp.plain.theta[i]), 2.0 * float(sp.plain.std[i]))
    report = {"parameters": {"Mq": {"value": -2.5, "std": 0.05}, "Ma": {"value": -7.0,
                                                                      "std": None},
                             "bq@0": {"value": 1.0, "std": 0.1}}}
    assert fwid.prior_from(report) == {"Mq": (-2.5, 0.05)}
    info = fwid.prior_information(report, ["Ma", "Mq"])
    np.testing.assert_allclose(info, np.diag([0.0, 1 / 0.05**2]))


def test_posterior_gradient_and_prior_jacobian_match_finite_differences(short_period):
    """The gradient the Gauss-Newton step uses, `sum J^T R^-1 v + W^2 (theta - mean)` (R
    from the residuals, Eq. 11), is that of the posterior cost `Eq. 10 + 1/2 |r_prior|^2`
    (central differences), and the prior residuals' Jacobian is `diag(1/std)`."""
    sp = short_period
    e = with_measured_x0(sp.model, sp.exps[0])
    names = list(sp.model.free)
    pb = prior_bounds(sp.model, names, {"Mq": (-2.0, 0.1), "Zde": (0.0, 0.05)})

    def residuals(theta):
        p = {**sp.model.params, **dict(zip(names, theta))}
        return e.z - simulate(sp.model, e, p)[1]

    noise = NoiseModel.of_data(e.z, e.mask, diagonal=False)

    @jax.jit
    def central_differences(theta, h):
        def cost(th):
            return noise.cost(residuals(th)) + pb.cost(th)

        steps = jnp.diag(h)
        return jax.vmap(lambda d: cost(theta + d) - cost(theta - d))(steps) / (2 * h)

    @jax.jit
    def gradient(theta):
        v, J = residuals(theta), jax.jacfwd(residuals)(theta)
        return pb.add_terms(*noise.gradient_terms(v, J), theta)[1]

    theta = jnp.asarray(sp.plain.theta) * 1.02 + 1e-3  # off the optimum
    g = gradient(theta)
    fd = central_differences(theta, 1e-6 * (1 + jnp.abs(theta)))
    np.testing.assert_allclose(np.asarray(g), np.asarray(fd), rtol=1e-5,
                               atol=1e-6 * float(jnp.max(jnp.abs(fd))))
    Jp = jax.jacfwd(pb.residuals)(theta)
    np.testing.assert_allclose(np.asarray(Jp), np.diag(np.asarray(pb.weight)), rtol=0, atol=0)
    assert np.asarray(pb.weight)[names.index("Mq")] == pytest.approx(10.0)


@pytest.mark.parametrize("prior, words", [
    ({"Mx": (0.0, 1.0)}, ["'Mx'", "not a free parameter", "Za", "Mde"]),
    ({"Mq": (0.0, 0.0)}, ["'Mq'", "std", "positive"]),
    ({"Mq": (0.0, -1.0)}, ["'Mq'", "positive"]),
    ({"Mq": (float("nan"), 1.0)}, ["'Mq'", "mean", "finite"]),
    ({"Mq": (1.0, 2.0, 3.0)}, ["'Mq'", "(mean, std)"]),
    ({"Mq": {"mean": 1.0, "sd": 2.0}}, ["'Mq'", "'sd'"]),
])
def test_bad_prior_is_one_line_input_error(short_period, prior, words):
    with pytest.raises(fwid.InputError) as err:
        fwid.fit(short_period.model, short_period.exps[0], prior=prior)
    msg = str(err.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_prior_needs_output_error(short_period):
    with pytest.raises(fwid.InputError, match="output-error"):
        fwid.fit(short_period.model, short_period.exps[0], prior={"Mq": (0.0, 1.0)},
                 method="multiple-shooting")
    with pytest.raises(fwid.InputError, match="output-error"):
        fwid.fit(short_period.model, short_period.exps[0], bounds={"Mq": (None, 0.0)},
                 method="filter-error")


def test_no_prior_is_the_plain_fit():
    """`PriorBounds.none` adds nothing: zero weight, infinite bounds."""
    pb = PriorBounds.none(3)
    H, g = pb.add_terms(jnp.eye(3), jnp.ones(3), jnp.arange(3.0))
    np.testing.assert_array_equal(np.asarray(H), np.eye(3))
    np.testing.assert_array_equal(np.asarray(g), np.ones(3))
    np.testing.assert_array_equal(np.asarray(pb.clip(jnp.array([-1e300, 0.0, 1e300]))),
                                  [-1e300, 0.0, 1e300])
