"""`flap-coupling`: the flight's own flapping series, whole or harmonic by harmonic,
modulated by the slow states and controls."""

import numpy as np

from fwid.diagnosis._regression import harmonic_series


def test_harmonics_sum_to_the_series_and_each_has_its_phase_derivative():
    phase = np.linspace(0.0, 20.0, 2001)
    coef = np.array([0.3, 1.0, 0.5, -0.2, 0.1, 0.05, 0.02])
    h, dh = harmonic_series(phase, coef)
    assert h.shape == dh.shape == (phase.size, 3)
    ref = sum(coef[2 * k - 1] * np.sin(k * phase) + coef[2 * k] * np.cos(k * phase)
              for k in (1, 2, 3))
    np.testing.assert_allclose(h.sum(axis=1), ref, atol=1e-12)
    np.testing.assert_allclose(dh[1:-1, 1], np.gradient(h[:, 1], phase)[1:-1], atol=2e-3)


def test_a_member_modulates_each_harmonic_on_its_own():
    from types import SimpleNamespace

    from fwid.diagnosis._catalogue.flap_coupling import MODULATIONS, Modulation, _columns

    n = 500
    phase = np.linspace(0.0, 60.0, n)
    h, dh = harmonic_series(phase, np.array([0.0, 1.0, 0.0, 0.5, 0.0, 0.2, 0.0]))
    w = np.sin(np.linspace(0.0, 3.0, n))
    s = SimpleNamespace(n=n, slow={"w": w})
    cols = _columns(s, "Z", Modulation(True, False, False, axis="lon"), h, dh)
    assert cols.shape == (n, 2 * 3 * 4)  # (h_k, h_k') x 3 harmonics x (u, w, q, de)
    k2w = 1 * 4 + 1  # the second harmonic times w
    np.testing.assert_allclose(cols[:, k2w], h[:, 1] * w)
    assert MODULATIONS[0].per_harmonic and MODULATIONS[0].smooth
