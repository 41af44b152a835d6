"""`nonlinear-aero` as additive smooth functions of the axis's states (and their products), its
size chosen by leave-one-flight-out error; the control's nonlinearity is the servo's."""

import numpy as np

from fwid.diagnosis._catalogue import get_effect
from fwid.diagnosis._catalogue._smooth import smooth_basis
from fwid.diagnosis._catalogue.nonlinear_aero import TERMS, Terms, columns_of


def _slow(n=3000, seed=0):
    rng = np.random.default_rng(seed)
    return {x: rng.normal(size=n) * s for x, s in (("u", 0.1), ("w", 0.2), ("q", 1.0),
                                                   ("de", 0.05))}


def test_members_columns_are_the_bases_and_products():
    slow = _slow()
    bases = {x: smooth_basis(v) for x, v in slow.items()}
    cols = columns_of(slow, "lon", Terms((1, 2), 2, True, bases))
    assert cols.shape == (3000, 2 + 2 + 1)
    np.testing.assert_array_equal(cols[:, :2], bases["w"](slow["w"])[:, :2])
    np.testing.assert_array_equal(cols[:, 4], slow["w"] * slow["q"])
    # the control is no variable of the family: no member reads it
    assert all(max(t.which) < 3 for t in TERMS)
    moved = dict(slow, de=slow["de"] * 10.0)
    for t in TERMS:
        np.testing.assert_array_equal(columns_of(moved, "lon", Terms(t.which, t.df, t.products,
                                                                      bases)),
                                      columns_of(slow, "lon", Terms(t.which, t.df, t.products,
                                                                     bases)))


def test_family_is_sized_the_largest_member_first_and_every_member_is_distinct():
    e = get_effect("nonlinear-aero")
    assert e.sized and e.variants == TERMS
    width = [columns_of(_slow(10), "lon", Terms(t.which, t.df, t.products,
                                                  {x: smooth_basis(v) for x, v in
                                                   _slow(200).items()})).shape[1]
             for t in TERMS]
    assert width[0] == max(width)
    assert len(set(TERMS)) == len(TERMS)


def test_a_member_is_equal_whatever_its_bases():
    """The bases are the fitting flights' and not part of a member's identity (the engine's
    caches key on it)."""
    a, b = Terms((0,), 2, bases={"u": None}), Terms((0,), 2)
    assert a == b and hash(a) == hash(b)
