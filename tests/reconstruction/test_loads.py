"""The loads of the full nonlinear rigid-body equations: exact on an exact nonlinear
manoeuvre, and each nonlinear term left out makes them measurably worse."""

import numpy as np
import pytest

from fwid.reconstruction._loads import TERMS, body_states, rigid_body_loads
from fwid.reconstruction._rotations import euler_to_matrix

from .helpers import VEHICLE, Motion

T = np.linspace(0.2, 3.8, 721)


@pytest.fixture(scope="module")
def truth():
    m = Motion(scale=1.5, seed=3)
    R, w, dw, V, dV = m.R(T), m.w(T), m.dw(T), m.V(T), m.dV(T)
    F, M = m.loads(T)
    return m, R, w, dw, V, dV, F, M


def _err(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def test_full_equations_match_world_frame_momentum(truth):
    m, R, w, dw, V, dV, F, M = truth
    Fc, Mc = rigid_body_loads(V, dV, w, dw, R, VEHICLE)
    assert _err(Fc, F) < 1e-6
    assert _err(Mc, M) < 1e-6


@pytest.mark.parametrize("term", TERMS)
def test_each_term_matters(truth, term):
    m, R, w, dw, V, dV, F, M = truth
    Fc, Mc = rigid_body_loads(V, dV, w, dw, R, VEHICLE, omit=(term,))
    err = _err(Fc, F) if term in ("transport", "gravity") else _err(Mc, M)
    assert err > 0.02, f"leaving out {term} changes the loads by only {err:.2%}"


def test_body_states_from_world_motion(truth):
    """V' from the world acceleration (`R^T a - w x V`) equals the body-axis derivative."""
    m, R, w, dw, V, dV, F, M = truth
    Vb, dVb, eul = body_states(R, m.vel(T), m.acc(T), w)
    assert _err(Vb, V) < 1e-9 and _err(dVb, dV) < 1e-6
    # this manoeuvre pitches through 90 deg: the angles change branch there, the attitude not
    assert np.allclose(euler_to_matrix(*eul.T), R, atol=1e-9)
    assert np.max(np.abs(np.diff(eul[:, 2]))) < 1.0  # psi continuous in time
