"""Eigenvalues and modes of an identified linear(ised) model (the paper's Tables 3 and 6)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from jaxtyping import Float

from ..models._greybox import GreyBoxModel


def eigenvalues(model: GreyBoxModel, consts: Mapping, params=None, *, x0=None,
                u0=None) -> Float[np.ndarray, " nx"]:
    """Eigenvalues of `A = df/dx` (the linearised Eq. 7; Tables 3 and 6).

    `A` is taken at `x0`, `u0` (default `x = 0, u = 0`, see `state_matrices` of
    [`fwid.GreyBoxModel`][]): the trim for fwid's DelFly models, whose states and inputs are
    perturbations from it; give the trim point for a model in absolute states.

    **Arguments:**

    - `model`: a [`fwid.GreyBoxModel`][].
    - `consts`: its constants (vehicle and trim).
    - `params`: parameter values (default: the model's).
    - `x0`, `u0`: the linearisation point (default zero).

    **Returns:** the eigenvalues, shape `(nx,)`, sorted by imaginary part, then real part.
    """
    A, _ = model.state_matrices(model.params if params is None else params, consts, x0, u0)
    ev = np.linalg.eigvals(np.asarray(A))
    return ev[np.lexsort((ev.real, -ev.imag))]


def modes(eigs) -> list[dict]:
    """Each mode's kind and numbers, from a model's eigenvalues (Tables 3 and 6).

    Oscillatory modes (one per conjugate pair) give the natural frequency `wn` [rad/s] and
    `natural_freq_hz` (`wn / 2 pi`), the damping ratio `zeta`, the damped frequency
    `damped_freq_hz` (`|Im lambda| / 2 pi`; also kept under its old name `freq_hz`) and the
    period of the damped oscillation; aperiodic modes give the time constant
    `tau = -1/lambda` (or the time to double when unstable).

    **Arguments:**

    - `eigs`: the eigenvalues ([`fwid.eigenvalues`][]).

    **Returns:** a list of dicts, one per mode, each with its `kind` (`"oscillatory"` or
    `"aperiodic"`) and the numbers above.
    """
    eigs = np.asarray(eigs, dtype=complex)
    out = []
    used = np.zeros(len(eigs), bool)
    for i, lam in enumerate(eigs):
        if used[i]:
            continue
        used[i] = True
        if abs(lam.imag) > 1e-9 * max(1.0, abs(lam)):
            # find its conjugate
            j = np.argmin(np.abs(eigs - np.conj(lam)) + used * 1e300)
            used[j] = True
            wn = abs(lam)
            out.append(dict(kind="oscillatory", eigenvalue=[lam.real, abs(lam.imag)],
                            wn=wn, zeta=-lam.real / wn, freq_hz=abs(lam.imag) / (2 * np.pi),
                            damped_freq_hz=abs(lam.imag) / (2 * np.pi),
                            natural_freq_hz=wn / (2 * np.pi),
                            period=2 * np.pi / abs(lam.imag), stable=bool(lam.real < 0)))
        else:
            re = lam.real
            out.append(dict(kind="aperiodic", eigenvalue=[re, 0.0],
                            tau=(-1.0 / re) if re != 0 else float("inf"),
                            t_double=(np.log(2) / re) if re > 0 else None,
                            stable=bool(re < 0)))
    return out
