"""`unsteady-aero`: the baseline's quasi-steady load (no control, not the load's own state)
through a causal filter, lagging part only, one column per load."""

import numpy as np
import pytest
from scipy.signal import lsim

from fwid.diagnosis._catalogue.unsteady_aero import (FILTERS, WAGNER_RATIO, Lagging,
                                                     lagging, quasi_steady, unsteady_states)

DT = 0.001
T = np.arange(0.0, 1.0, DT)


def test_the_load_never_lags_its_own_state():
    assert unsteady_states("M") == ("u", "w") and unsteady_states("Z") == ("u", "q")
    assert unsteady_states("L") == ("v",) and "de" not in unsteady_states("X")


def test_the_indicial_member_is_jones_two_pole_response():
    """A step through the indicial member: the lagging part follows
    `-(0.67 exp(-t/tau) + 0.33 exp(-t/6.6 tau))` (Jones's approximation of Wagner's function,
    normalised to its lag), computed here by scipy's continuous-time simulation."""
    x = np.where(T >= 0.1, 1.0, 0.0)
    tau = 0.03
    got = lagging(x, DT, Lagging("indicial", tau))
    ref = np.zeros_like(T)
    for share, t in ((0.335 / 0.5, tau), (0.165 / 0.5, WAGNER_RATIO * tau)):
        _, y, _ = lsim(([1.0], [t, 1.0]), x, T)
        ref += share * y
    np.testing.assert_allclose(got, ref - x, atol=2e-2)
    assert got[np.searchsorted(T, 0.1) + 1] == pytest.approx(-1.0, abs=0.05)


def test_the_column_is_the_quasi_steady_load_lagged():
    rng = np.random.default_rng(1)
    slow = {"u": rng.normal(size=T.size), "w": rng.normal(size=T.size)}
    m = Lagging("lag", 0.05, {"M": {"u": 0.2, "w": -0.7}})
    qs = quasi_steady(slow, "M", m, T.size)
    np.testing.assert_allclose(qs, 0.2 * slow["u"] - 0.7 * slow["w"])
    delayed = lagging(qs, DT, Lagging("delay", 0.02)) + qs
    np.testing.assert_allclose(delayed[:20], qs[0])  # steady before the first sample
    np.testing.assert_allclose(delayed[20:], qs[:-20], atol=1e-12)
    assert {f.kind for f in FILTERS} == {"lag", "indicial", "delay"}
    assert Lagging.from_json(m.to_json()) == m


def test_the_family_holds_only_lags_the_band_resolves():
    """Below the 5 Hz split a lag shorter than 1 / (2 pi 5 Hz) is a rate on every frequency
    of the band: such members are not in the bound family; a lower split drops more."""
    from types import SimpleNamespace

    from fwid.diagnosis._catalogue import get_effect
    from fwid.diagnosis._catalogue.unsteady_aero import resolved

    assert not resolved(Lagging("lag", 0.03), 5.0) and resolved(Lagging("lag", 0.05), 5.0)
    assert not resolved(Lagging("delay", 0.05), 2.0) and resolved(Lagging("lag", 0.1), 2.0)
    e = get_effect("unsteady-aero")
    engine = SimpleNamespace(loads=("M",), cutoff=5.0,
                             fit=lambda idx, ch, model: (np.array([0.1, -0.2, 0.3, 0.4]), 0.0))
    bound = e.bound(engine, (0,))
    assert bound.variants and all(v.tau >= 1 / (2 * np.pi * 5.0) for v in bound.variants)
    assert bound.variants[0].derivatives == {"M": {"u": 0.1, "w": -0.2}}


def test_only_the_entry_that_filters_the_states_must_whiten_the_residual():
    from fwid.diagnosis._catalogue import CATALOGUE

    assert [e.name for e in CATALOGUE if e.filters_states] == ["unsteady-aero"]
