"""Smooth functions of one signal, of a chosen number of degrees of freedom.

A penalised regression spline (Eilers & Marx's P-spline: a cubic B-spline basis on
`KNOTS` equally spaced knots over the range of the fitting flights, from scipy, with a second-difference
penalty on its coefficients) is reduced to its smoothest components: the eigenvectors of the
penalty in the metric of the data (Demmler & Reinsch), smoothest first, made in the
complement of the constant and the linear function, which the baseline already has (a
flight's trim and the derivative of Eqs. 2-6). What remains,
`Smooth(x)[:, :df]`, is the best `df`-dimensional smooth space beyond the linear one, so a
family that keeps `df` components is a penalised spline of `df` effective degrees of freedom
(a quadratic bend first, then the odd one that saturates, then finer shapes), whose `df` is
chosen inside the fitting flights by leave-one-flight-out error (`Effect.sized`).

Outside the range the basis was made on, each component holds its value at the nearer end
(a flight that moves further than the fitting flights is not extrapolated: a cubic piece
would blow up, and the edge slope of a fine component is steep).
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np
from scipy.interpolate import BSpline, PPoly
from scipy.linalg import eigh, null_space

#: B-splines per signal (cubic, equally spaced knots over its range).
KNOTS = 10
#: Most smooth components kept beyond the linear ones.
MAX_DF = 4


@dataclasses.dataclass(frozen=True, eq=False)
class Smooth:
    """`MAX_DF` smooth functions of one signal (see the module docstring), each of unit RMS
    over the data it was made on, as piecewise cubics (`breaks`, `coef` `(4, pieces, df)`,
    highest power first), constant beyond `breaks[0]`, `breaks[-1]`."""

    breaks: np.ndarray
    coef: np.ndarray
    #: `at`'s values by the signal they were taken of (not part of the function).
    _memo: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    def at(self, x: np.ndarray) -> np.ndarray:
        """`self(x)` for a signal array that is evaluated again and again (a flight's
        cycle-averaged state, once per member and load that reads it): kept while `x`
        lives, so every member slices the one evaluation, and dropped when it goes."""
        key = id(x)
        held = self._memo.get(key)
        if held is not None and held[0]() is x:
            return held[1]
        value = self(x)
        memo = self._memo
        self._memo[key] = (weakref.ref(x, lambda _, k=key: memo.pop(k, None)), value)
        return value

    def __call__(self, x, xp=np):
        """The components at `x` (any shape): `x.shape + (df,)`; `xp` the array module
        (`jax.numpy` inside a model's equations)."""
        breaks, coef = xp.asarray(self.breaks), xp.asarray(self.coef)
        xc = xp.clip(xp.asarray(x, dtype=float), breaks[0], breaks[-1])
        # in JAX, inside the equations' integration loop: a dozen comparisons at once beat
        # a binary search's sequential loop (a fifth of an augmented fit's time)
        how = {} if xp is np else {"method": "compare_all"}
        i = xp.clip(xp.searchsorted(breaks, xc, side="right", **how) - 1, 0,
                    len(self.breaks) - 2)
        d = (xc - breaks[i])[..., None]
        c = coef[:, i, :]
        return ((c[0] * d + c[1]) * d + c[2]) * d + c[3]

    def to_json(self) -> dict:
        return {"breaks": self.breaks.tolist(), "coef": self.coef.tolist()}

    @classmethod
    def from_json(cls, d: dict) -> Smooth:
        return cls(np.asarray(d["breaks"], dtype=float), np.asarray(d["coef"], dtype=float))


def smooth_basis(x: np.ndarray, knots: int = KNOTS, df: int = MAX_DF) -> Smooth | None:
    """The smooth components of the signal whose pooled samples are `x` (module docstring);
    `None` when it hardly moves (nothing to bend)."""
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    if x.size < 4 * knots:
        return None
    lo, hi = float(np.min(x)), float(np.max(x))
    if not hi - lo > 1e-9 * max(abs(lo), abs(hi), 1.0):
        return None
    t = np.r_[[lo] * 3, np.linspace(lo, hi, knots - 2), [hi] * 3]
    sample = x[:: max(1, x.size // 20000)]
    B = BSpline.design_matrix(sample, t, 3).toarray()
    G = B.T @ B / len(sample)
    D = np.diff(np.eye(knots), 2, axis=0)
    P = D.T @ D
    G += 1e-9 * np.trace(G) / knots * np.eye(knots)
    # the constant and the linear function (coefficients 1 and the Greville abscissae) are
    # the baseline's: the components are made in their complement (in the data's metric)
    greville = (t[1:-3] + t[2:-2] + t[3:-1]) / 3.0
    Q = null_space(np.stack([np.ones(knots), greville]) @ G)
    _, A = eigh(Q.T @ P @ Q, Q.T @ G @ Q)  # A^T Q^T G Q A = I, smoothest first
    V = Q @ A[:, :df]
    pieces = [PPoly.from_spline(BSpline(t, V[:, k], 3)) for k in range(V.shape[1])]
    keep = np.r_[True, np.diff(pieces[0].x) > 0]  # drop the knots' zero-length pieces
    breaks = pieces[0].x[keep]
    coef = np.stack([p.c[:, keep[1:]] for p in pieces], axis=-1)
    return Smooth(breaks, coef)
