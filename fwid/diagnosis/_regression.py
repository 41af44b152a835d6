"""Least squares with flight-local terms: the fast engine of the gap diagnosis.

Every load is modelled, per flight (or block), as

    y = G theta + L lambda_k + e,

where `G` holds the global regressors (the cycle-averaged model of Eqs. 2-6 and any
candidate effect's columns, shared by every flight) and `L` the local ones: a constant (the
flight's trim load and bias) and the 3-harmonic Fourier series of Eq. (12) in the measured
flapping phase. The local part is re-estimated on every flight, held-out ones included, as
fwid does with bias terms: a flight's flapping phase origin and trim are its own, the
physics in `theta` is not.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: Harmonics of the local flapping series (Eq. 12).
HARMONICS = 3


def local_design(phase: np.ndarray, harmonics: int = HARMONICS) -> np.ndarray:
    """`[1, sin(phi), cos(phi), ..., sin(n phi), cos(n phi)]`, shape `(n, 1 + 2 harmonics)`."""
    cols = [np.ones_like(phase)]
    for k in range(1, harmonics + 1):
        cols += [np.sin(k * phase), np.cos(k * phase)]
    return np.stack(cols, axis=1)


def harmonic_series(phase: np.ndarray, coef: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The flapping series of Eq. (12) with local coefficients `coef` (as `local_design`,
    constant first), harmonic by harmonic, and each harmonic's derivative with respect to the
    phase: two arrays `(n, harmonics)` (their row sums are the series and its derivative)."""
    k = np.arange(1, (len(coef) - 1) // 2 + 1)
    a, b = coef[1::2][: len(k)], coef[2::2][: len(k)]
    s, c = np.sin(phase[:, None] * k), np.cos(phase[:, None] * k)
    return a * s + b * c, k * (a * c - b * s)


class Projector:
    """Removes a flight's local terms: `x - Q Q^T x` with `Q` an orthonormal basis of `L`."""

    def __init__(self, local: np.ndarray):
        self.q, self.r = np.linalg.qr(local)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return x - self.q @ (self.q.T @ x)

    def coefficients(self, local: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Least-squares local coefficients of `x` (for `harmonic_series`)."""
        return np.linalg.solve(self.r, self.q.T @ x)


#: Eigenvalues of the scaled Gram matrix below this fraction of the largest are dropped
#: (singular values below 1e-6 of the largest: a rank-deficient design).
GRAM_RCOND = 1e-12


def normal_equations(design: np.ndarray, target: np.ndarray, projector: Projector
                     ) -> tuple[np.ndarray, np.ndarray, float]:
    """One unit's share of the normal equations, its local terms projected out:
    `(A^T A, A^T b, b^T b)` with `A = P G`, `b = P y`. Sums of these over units give the fit on
    any set of units (`solve`) without touching the samples again."""
    a = projector(design) if design.shape[1] else design
    b = projector(target)
    return a.T @ a, a.T @ b, float(b @ b)


def solve(parts: Sequence[tuple[np.ndarray, np.ndarray, float]]) -> tuple[np.ndarray, float]:
    """Global coefficients `theta` minimising `sum_k |P_k (y_k - G_k theta)|^2`, and that
    minimum (the training error, local terms re-estimated), from the units' normal equations
    (`normal_equations`), by `solve_stack`."""
    ata = sum(p[0] for p in parts)
    atb = sum(p[1] for p in parts)
    btb = float(sum(p[2] for p in parts))
    theta = solve_stack(np.asarray(ata)[None], np.asarray(atb)[None])[0]
    return theta, max(float(error((ata, atb, btb), theta)), 0.0)


def solve_stack(ata: np.ndarray, atb: np.ndarray) -> np.ndarray:
    """The least-squares coefficients of a stack of normal equations `ata` `(s, k, k)`,
    `atb` `(s, k)`: `(s, k)`, each solved on its own (one batched eigen-decomposition).

    Columns are scaled to unit norm first and rank deficiency (a column that never moves,
    e.g. the rudder in an elevator manoeuvre) is handled by dropping it and by the
    pseudo-inverse of the Gram matrix (eigenvalues below `GRAM_RCOND` of the largest).
    """
    s, k = atb.shape
    theta = np.zeros((s, k))
    if not k:
        return theta
    norms = np.sqrt(np.maximum(np.diagonal(ata, axis1=1, axis2=2), 0.0))
    live = norms > 1e-12 * np.maximum(norms.max(axis=1), 1e-300)[:, None]
    if not np.all(live == live[:1]):  # columns dropped in some members only: one by one
        return np.concatenate([solve_stack(ata[j:j + 1], atb[j:j + 1]) for j in range(s)])
    cols = live[0]
    if not np.any(cols):
        return theta
    n = norms[:, cols]
    w, v = np.linalg.eigh(ata[:, cols][:, :, cols] / (n[:, :, None] * n[:, None, :]))
    keep = w > GRAM_RCOND * np.maximum(w[:, -1:], 1e-300)
    proj = np.einsum("sji,sj->si", v, atb[:, cols] / n)
    sol = np.einsum("sij,sj->si", v, np.where(keep, proj / np.where(keep, w, 1.0), 0.0))
    theta[:, cols] = sol / n
    return theta


def error(part: tuple[np.ndarray, np.ndarray, float], theta: np.ndarray):
    """`|b - A theta|^2` from normal equations `(A^T A, A^T b, b^T b)` (one unit's, or a sum):
    a fit's training error, or a unit's error under a fit to other units. Over stacks too:
    `(s, k, k)`, `(s, k)`, `(s,)` and `theta` `(s, k)` give the `(s,)` errors."""
    ata, atb, btb = part
    return (btb - 2.0 * np.einsum("...k,...k->...", theta, atb)
            + np.einsum("...k,...kl,...l->...", theta, ata, theta))


def residual(design: np.ndarray, target: np.ndarray, projector: Projector, theta) -> np.ndarray:
    """The flight's residual once `theta` is applied and its local terms are re-estimated."""
    return projector(target - design @ theta) if design.shape[1] else projector(target)
