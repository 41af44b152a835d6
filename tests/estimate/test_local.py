"""Bias terms re-estimated on a new flight (`refit_local_affine`)."""

import numpy as np

import fwid
from fwid.estimate import refit_local_affine
from fwid.estimate._local import _whitener
from fwid.models import TABLE1, longitudinal
from fwid.simulation import Experiment

from .conftest import LON_CONSTS


def test_whitener_inverts_a_covariance_and_survives_a_singular_one():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((4, 4))
    R = A @ A.T + 0.1 * np.eye(4)
    W = _whitener(R)
    np.testing.assert_allclose(W.T @ W, np.linalg.inv(R), rtol=1e-10)
    v = rng.standard_normal(4)
    W = _whitener(np.outer(v, v))  # rank one: no Cholesky factor
    assert np.all(np.isfinite(W))


def test_residuals_proportional_across_outputs_do_not_stop_it():
    """A flight whose outputs' residuals are exactly proportional (what a diverging
    simulation leaves: one growing mode in every output) made the Cholesky factor of their
    covariance fail; the estimate is still returned."""
    model = longitudinal(dict(TABLE1, bq=0.01, bu=-0.003))
    t = np.arange(0, 4, 0.01)
    u = np.where((t > 1) & (t < 1.5), 0.1, 0.0)[:, None]
    exp = Experiment(t, u, np.zeros((len(t), 4)), x0=np.zeros(4), consts=LON_CONSTS)
    y = np.asarray(fwid.simulate(model, exp)[1])
    ramp = np.exp(t)[:, None] * np.array([1.0, 2.0, -1.0, 0.5])  # one mode, every output
    exp = Experiment(t, u, y + ramp, x0=np.zeros(4), consts=LON_CONSTS)
    values = refit_local_affine(model, exp)
    assert values is not None and set(values) == set(model.local)
    assert all(np.isfinite(v) for v in values.values())
