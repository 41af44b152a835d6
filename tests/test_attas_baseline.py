"""Checks of the independent numpy/scipy baseline (benchmarks/peers/scipy_output_error.py) on real ATTAS data.

TEMPORARY: this tests the *reference* estimator, not fwid. It is to be superseded by fwid's
own ATTAS test (which should compare fwid against the same published values). Skipped when
the Jategaonkar flight data are not available (set FWID_FLIGHTDATA).
"""

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from peers.scipy_output_error import fit_output_error, rk4_simulate  # noqa: E402
from cases.attas import (  # noqa: E402
    TC11_BOOK_OEM,
    TC11_THETA0,
    default_folder,
    load_attas_tc11,
    tc11_xdot,
)

HAVE_DATA = (default_folder() / "fAttasElv1.mat").exists()
needs_data = pytest.mark.skipif(not HAVE_DATA, reason="ATTAS flight data not available")


def test_rk4_matches_exact_linear_response():
    # x' = A x + b u with u linear in time between samples: RK4 with the mid-step mean is
    # 4th-order accurate, so at dt = 0.01 it must agree with the exact solution closely.
    A = np.array([[-0.5, 1.0], [-4.0, -1.0]])
    b = np.array([0.2, -3.0])
    t = np.arange(0.0, 3.0, 0.01)
    u = np.sin(2.0 * t)
    x0 = np.array([0.1, 0.0])
    X = rk4_simulate(lambda x, uu, th: A @ x + b * uu[0], None, t, u, x0)
    # reference: exact discretisation of the piecewise-linear input (augmented matrix exp.)
    n = 2
    M = np.zeros((n + 2, n + 2))
    M[:n, :n] = A
    M[:n, n] = b
    M[n, n + 1] = 1.0
    x = x0.copy()
    for k in range(len(t) - 1):
        h = t[k + 1] - t[k]
        slope = (u[k + 1] - u[k]) / h
        E = expm(M * h)
        x = E[:n, :n] @ x + E[:n, n] * u[k] + E[:n, n + 1] * slope
    assert np.allclose(X[-1], x, atol=1e-8)


@needs_data
def test_tc11_reproduces_book_exactly_with_book_setup():
    # Book setup: diagonal R, both manoeuvres started from fAttasElv1's first sample.
    recs = load_attas_tc11(x0_mode="book")
    res = fit_output_error(
        tc11_xdot, TC11_THETA0,
        [r["t"] for r in recs], [r["u"] for r in recs], [r["z"] for r in recs],
        [r["x0"] for r in recs], diag_R=True,
    )
    assert res["converged"]
    np.testing.assert_allclose(res["theta"], TC11_BOOK_OEM, rtol=1e-4)
    assert np.all(res["std"] > 0) and np.all(res["std"] < 0.05 * np.abs(res["theta"]) + 1e-3)


@needs_data
def test_tc11_own_initial_states_full_R_within_2pct():
    # fwid's setup: each manoeuvre from its own first sample, full R (paper Eq. 11).
    recs = load_attas_tc11()
    res = fit_output_error(
        tc11_xdot, TC11_THETA0,
        [r["t"] for r in recs], [r["u"] for r in recs], [r["z"] for r in recs],
        [r["x0"] for r in recs],
    )
    rel = np.abs(res["theta"] / TC11_BOOK_OEM - 1.0)
    assert np.all(rel < 0.02), rel
