"""No silent failure: a fit that should not be trusted says so with a FitWarning."""

import re
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.estimate import fit_warnings

T = np.arange(400) * 0.01
U = np.sign(np.sin(2 * T))


def _sum_lag():
    """`a1` and `a2` only enter as their sum."""
    def f(x, u, p, c):
        return jnp.stack([-(p["a1"] + p["a2"]) * x[0] + p["b"] * u[0]])

    return fwid.GreyBoxModel(f, states=("x",), inputs=("u",), name="lag",
                             params=dict(a1=1.0, a2=0.5, b=1.0))


def _data(model, ny=1, noise=0.01, seed=0):
    _, ys = fwid.simulate(model, fwid.Experiment(T, U, np.zeros((T.size, ny)), x0=np.zeros(1)))
    rng = np.random.default_rng(seed)
    return np.asarray(ys) + noise * rng.standard_normal((T.size, ny))


def _simple(h=None, outputs=None, name="lag"):
    return fwid.GreyBoxModel(lambda x, u, p, c: jnp.stack([-p["a"] * x[0] + p["b"] * u[0]]),
                             states=("x",), inputs=("u",), params=dict(a=1.0, b=1.0),
                             h=h, outputs=outputs, name=name)


def _twice():
    """The state measured twice, the second copy with almost no noise of its own: R nearly
    singular."""
    model = _simple(h=lambda x, u, p, c: jnp.stack([x[0], x[0]]), outputs=("y1", "y2"),
                    name="twice")
    z = _data(model.with_params(a=3.0, b=2.0), ny=2)[:, :1]
    rng = np.random.default_rng(1)
    return model, np.concatenate([z, z + 1e-7 * rng.standard_normal(z.shape)], axis=1)


def _fit(model, z, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = fwid.fit(model, fwid.Experiment(T, U, z, x0=np.zeros(1)), names=["f1"], **kw)
    return r, [str(w.message) for w in caught if issubclass(w.category, fwid.FitWarning)]


def test_fitwarning_is_a_userwarning_users_can_filter():
    assert issubclass(fwid.FitWarning, UserWarning)


def test_not_converged_warns_and_is_in_the_result():
    model = _simple()
    z = _data(model.with_params(a=3.0, b=2.0))
    r, caught = _fit(model, z, start="model", max_steps=1)
    assert not bool(r.converged)
    msg = "f1: the lag fit did not converge in 1 Gauss-Newton step (max_steps=1)"
    assert any(m.startswith(msg) for m in caught), caught
    assert any(m.startswith(msg) for m in r.warnings)


def test_a_good_fit_has_no_warnings():
    model = _simple()
    r, caught = _fit(model, _data(model.with_params(a=3.0, b=2.0)), start="model")
    assert bool(r.converged) and r.warnings == () and caught == []


def test_parameters_entering_as_a_sum_are_named():
    """Only their sum is identifiable: the information matrix is singular, the estimates have
    no correlation, and the warning names the pair from the collinear sensitivities."""
    model = _sum_lag()
    r, caught = _fit(model, _data(model.with_params(a1=1.2, a2=0.8)), start="model")
    found = [m for m in caught if "information matrix is singular" in m]
    assert found and "a1 and a2 (+1.0000)" in found[0] and "collinear beyond 0.98" in found[0]
    assert "fix a1 at a value you trust" in found[0] and ".with_free(...)" in found[0]


def _numbers(text):
    return [float(x) for x in re.findall(r"[+-]\d+\.\d+", text)]


def test_an_indefinite_covariance_has_no_correlation_beyond_one():
    """A covariance inverted from a numerically singular information matrix need not be
    positive semi-definite; its "correlations" (here +7.2) are no correlations: NaN, and the
    warning names the pairs the information cannot separate, every number within [-1, 1]."""
    from fwid.estimate import correlation
    from fwid.estimate._warnings import unidentifiable

    cov = jnp.array([[1.0, 7.2, 0.0], [7.2, 1.0, 0.0], [0.0, 0.0, 1.0]])
    assert np.all(np.isnan(np.asarray(correlation(cov))))
    good = jnp.array([[4.0, 1.0 + 1e-12], [1.0 + 1e-12, 0.25]])  # +1 up to rounding: clipped
    assert float(jnp.max(correlation(good))) == 1.0
    model = _simple()
    r, _ = _fit(model, _data(model.with_params(a=3.0, b=2.0)), start="model")
    bad = r.__class__(**{**{k: getattr(r, k) for k in r.__dataclass_fields__},
                         "corr": correlation(jnp.array([[1.0, 7.2], [7.2, 1.0]])),
                         "warnings": ()})
    M = np.array([[1.0, 1.0 - 1e-13], [1.0 - 1e-13, 1.0]])
    found = [m for m in fit_warnings(bad, ["f1"], information=M) if "singular" in m]
    assert found and "a and b" in found[0], found
    assert all(abs(x) <= 1 for x in _numbers(found[0]))
    # x, y and their sum: no pair collinear, the three together singular
    J = np.random.default_rng(0).standard_normal((50, 3))
    J = np.column_stack([J[:, 0], J[:, 1], J[:, 0] + J[:, 1], J[:, 2]])
    assert sorted(unidentifiable(J.T @ J, ["x", "y", "s", "z"])) == ["s", "x", "y"]
    singular = fit_warnings(bad, ["f1"], information=J[:, :2].T @ J[:, :2] * [[1, 0], [0, 0]])
    assert any("singular" in m for m in singular)


def test_nearly_correlated_pair_is_named_with_its_correlation():
    def f(x, u, p, c):  # a2 nearly only through the sum: corr(a1, a2) close to -1
        return jnp.stack([-(p["a1"] + p["a2"]) * x[0] + p["b"] * u[0] + 0.03 * p["a2"] * x[0] ** 2])

    model = fwid.GreyBoxModel(f, states=("x",), inputs=("u",),
                              params=dict(a1=1.0, a2=0.5, b=1.0), name="near")
    r, caught = _fit(model, _data(model.with_params(a1=1.2, a2=0.8)), start="model")
    found = [m for m in caught if "nearly unidentifiable" in m]
    assert found and "a1 and a2 (" in found[0]
    assert abs(float(r.corr[0, 1])) > 0.98


def test_ill_conditioned_R_says_the_condition_number():
    model, z2 = _twice()
    r, caught = _fit(model, z2, start="model", noise="full")
    assert r.noise == "full"
    found = [m for m in caught if "ill-conditioned" in m]
    assert found and "f1: the twice fit: the noise covariance R is ill-conditioned " \
                     "(condition number " in found[0]
    assert found[0].endswith("next: noise='diagonal'")


def test_non_finite_estimate_is_reported():
    model = _simple()
    r, _ = _fit(model, _data(model.with_params(a=3.0, b=2.0)), start="model")
    bad = r.__class__(**{**{k: getattr(r, k) for k in r.__dataclass_fields__},
                         "theta": jnp.array([jnp.nan, 1.0]), "warnings": ()})
    assert fit_warnings(bad, ["f1"])[0].startswith("f1: the lag fit diverged")
    nan_std = r.__class__(**{**{k: getattr(r, k) for k in r.__dataclass_fields__},
                             "std": jnp.array([jnp.nan, 1.0]), "warnings": ()})
    assert "non-finite standard deviations" in fit_warnings(nan_std, ["f1"])[0]


def test_fit_each_warns_per_flight():
    model = _simple()
    exps = [fwid.Experiment(T, U, _data(model.with_params(a=3.0, b=2.0), seed=s), x0=np.zeros(1))
            for s in (0, 1)]
    with pytest.warns(fwid.FitWarning, match="g2: the lag fit did not converge"):
        rs = fwid.fit_each(model, exps, names=["g1", "g2"], start="model", max_steps=1)
    assert all(r.warnings for r in rs)


def test_auto_noise_falls_back_to_a_diagonal_R_and_says_so():
    model, z2 = _twice()
    r, caught = _fit(model, z2, start="model")  # noise="auto", the default
    assert r.noise == "diagonal" and bool(r.converged)
    assert np.count_nonzero(np.asarray(r.R) - np.diag(np.diag(np.asarray(r.R)))) == 0
    note = [m for m in caught if "with a full R ended with an ill-conditioned R" in m]
    assert note and "estimates are those of a diagonal R" in note[0]
    assert abs(float(r.params["a"]) - 3.0) < 0.05
    exps = [fwid.Experiment(T, U, z2, x0=np.zeros(1))] * 2
    with pytest.warns(fwid.FitWarning, match="g1: the twice fit with a full R"):
        each = fwid.fit_each(model, exps, names=["g1", "g2"], start="model")
    assert [e.noise for e in each] == ["diagonal", "diagonal"]
    assert fwid.fit(model, exps[0], start="model", noise="diagonal").noise == "diagonal"
    with pytest.raises(ValueError, match="noise must be one of 'auto', 'full', 'diagonal'"):
        fwid.fit(model, exps[0], noise="fool")


def test_coloured_correlated_residuals_say_model_error_and_auto_uses_a_diagonal_R():
    """A missing effect (a slow sine the model lacks) in both outputs: residuals coloured
    and correlated between the outputs. The warning names it; noise='auto' keeps the
    diagonal-R estimates."""
    model = _simple(h=lambda x, u, p, c: jnp.stack([x[0], 2.0 * x[0]]), outputs=("y1", "y2"),
                    name="twice")
    z = _data(model.with_params(a=3.0, b=2.0), ny=2, noise=0.005)
    z = z + 0.05 * np.sin(1.3 * T)[:, None] * np.array([1.0, 1.5])
    r, caught = _fit(model, z, start="model")
    assert r.noise == "diagonal"
    assert float(np.max(np.asarray(r.lag1))) > 0.8
    assert any("model error, not measurement noise" in m for m in caught), caught
    assert any("strongly coloured" in m and "process noise or a missing effect" in m
               and "y1 and y2" in m and m.endswith("next: fwid.fit(..., method='filter-error')")
               for m in caught), caught


def test_least_squares_start_of_a_model_with_h_says_it_keeps_the_nominal_values():
    model = _simple(h=lambda x, u, p, c: jnp.stack([x[0], 2.0 * x[0]]), outputs=("y1", "y2"),
                    name="twice")
    z = _data(model.with_params(a=3.0, b=2.0), ny=2)
    _, caught = _fit(model, z)  # start="least-squares", the default
    assert any(m.startswith("twice: the least-squares start keeps the nominal values of a, b")
               for m in caught), caught


def test_quiet_fits_silences_its_own_thread_only():
    """A fit run in a worker thread inside `quiet_fits` issues nothing, while the thread
    beside it still warns (the diagnosis runs the baseline's fit so, next to its selection)."""
    import threading

    from fwid.estimate import quiet_fits
    from fwid.estimate._warnings import issue

    inside, go = threading.Event(), threading.Event()

    def worker():
        with quiet_fits():
            inside.set()
            go.wait(5)
            issue(["worker: quiet"])

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t = threading.Thread(target=worker)
        t.start()
        inside.wait(5)
        issue(["main: heard"])
        go.set()
        t.join(5)
    assert [str(w.message) for w in caught] == ["main: heard"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        issue(["after: heard"])
    assert len(caught) == 1
