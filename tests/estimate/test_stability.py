"""The unstable-model warning (fwid/estimate/_stability.py) against the analytic eigenvalues."""

import jax.numpy as jnp
import numpy as np

import fwid
from fwid.estimate._stability import GROWTH_MAX, fastest_growth, instability_warning


def _model(a11, a12, a21, a22):
    """x' = A x + b u, linear: the eigenvalues of A are the modes, wherever it is linearised."""
    def f(x, u, p, c):
        return jnp.stack([p["a11"] * x[0] + p["a12"] * x[1] + u[0],
                          p["a21"] * x[0] + p["a22"] * x[1]])

    return fwid.GreyBoxModel(f, states=("x1", "x2"), inputs=("u",), name="lin",
                             params=dict(a11=a11, a12=a12, a21=a21, a22=a22))


def _exp(seconds, dt=0.05):
    t = np.arange(int(round(seconds / dt)) + 1) * dt
    return fwid.Experiment(t, np.sin(t), np.zeros((t.size, 2)), x0=np.array([0.1, -0.2]))


def test_growth_is_the_largest_real_eigenvalue_and_the_warning_needs_a_long_enough_record():
    m = _model(-1.4, 43.1, 0.22, -3.7)  # FVSysID TC08's short period: one real mode > 0
    lam = np.max(np.linalg.eigvals(np.array([[-1.4, 43.1], [0.22, -3.7]])).real)
    assert abs(fastest_growth(m, _exp(2.0)) - lam) < 1e-12
    short = np.log(GROWTH_MAX) / lam * 0.8  # grows 100**0.8 = 40-fold: no warning
    assert instability_warning(m, [_exp(short)], ["s"]) is None
    note = instability_warning(m, [_exp(12.5)], ["f1"])
    assert note.startswith("f1: the lin model identified is unstable")
    assert f"eigenvalue {lam:+.3g} 1/s" in note and note.endswith("next: fwid.fit(..., method='multiple-shooting')")
    assert f"{np.exp(lam * 12.5):.3g}-fold over the 12.5 s record" in note


def test_stable_and_stateless_models_never_warn():
    stable = _model(-1.4, 43.1, -0.5, -3.7)
    assert fastest_growth(stable, _exp(1.0)) < 0
    assert instability_warning(stable, [_exp(100.0)], ["f"]) is None
    oscillating = _model(0.0, 1.0, -4.0, 0.0)  # undamped: real part 0, never "unstable"
    assert instability_warning(oscillating, [_exp(100.0)], ["f"]) is None
