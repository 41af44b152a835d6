"""The smooth components of one signal (`_smooth.py`): beyond the linear ones, orthonormal on
the data they were made on, smoothest first, and spanning the shapes a family needs."""

import numpy as np
import pytest

from fwid.diagnosis._catalogue._smooth import MAX_DF, Smooth, smooth_basis

RNG = np.random.default_rng(3)
X = RNG.normal(size=4000) * 0.2


def _explained(y, cols):
    """Share of `y`'s variance beyond `[1, x]` that `cols` explain (least squares)."""
    base = np.column_stack([np.ones_like(X), X])
    r0 = y - base @ np.linalg.lstsq(base, y, rcond=None)[0]
    full = np.column_stack([base, cols])
    r = y - full @ np.linalg.lstsq(full, y, rcond=None)[0]
    return 1.0 - r.var() / r0.var()


def test_components_are_orthonormal_and_beyond_the_linear_ones():
    b = smooth_basis(X)
    Y = b(X)
    assert Y.shape == (X.size, MAX_DF)
    np.testing.assert_allclose(Y.T @ Y / X.size, np.eye(MAX_DF), atol=1e-6)
    # the constant and the linear function, which the baseline has, are not in them
    np.testing.assert_allclose(np.column_stack([np.ones_like(X), X]).T @ Y / X.size, 0.0,
                               atol=1e-6)


def test_the_first_component_is_even_the_second_odd():
    """A square is one component, `x|x|` (odd) needs the second, a saturation four: the
    family's degrees of freedom order its shapes from the bend to finer ones."""
    Y = smooth_basis(X)(X)
    assert _explained(X * X, Y[:, :1]) > 0.97
    assert _explained(X * np.abs(X), Y[:, :1]) < 0.05
    assert _explained(X * np.abs(X), Y[:, :2]) > 0.95
    tanh = 0.1 * np.tanh(X / 0.1)
    assert _explained(tanh, Y[:, :4]) > 0.9 > _explained(tanh, Y[:, :1])


def test_outside_the_range_it_holds_the_end_values_and_reads_back():
    b = smooth_basis(X)
    lo, hi = X.min(), X.max()
    np.testing.assert_allclose(b(np.array([lo - 5.0, hi + 5.0])), b(np.array([lo, hi])))
    back = Smooth.from_json(b.to_json())
    np.testing.assert_array_equal(back(X), b(X))


@pytest.mark.parametrize("x", [np.zeros(500), np.ones(10)])
def test_a_signal_that_does_not_move_has_no_components(x):
    assert smooth_basis(x) is None


def test_at_evaluates_a_signal_once_while_it_lives_and_forgets_it_after():
    basis = smooth_basis(np.linspace(-1.0, 1.0, 400))
    x = np.linspace(-0.5, 0.5, 50)
    first = basis.at(x)
    np.testing.assert_array_equal(first, basis(x))
    assert basis.at(x) is first  # the one evaluation, kept
    y = x.copy()  # equal values, another signal: evaluated on its own
    assert basis.at(y) is not first
    assert len(basis._memo) == 2
    del x, first, y
    assert basis._memo == {}  # nothing kept for signals that are gone
