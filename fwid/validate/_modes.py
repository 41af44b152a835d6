"""Eigenvalues and modes of an identified linear(ised) model (the paper's Tables 3 and 6)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..models._greybox import GreyBoxModel


def eigenvalues(model: GreyBoxModel, consts: Mapping, params=None) -> np.ndarray:
    """Eigenvalues of `A = df/dx` at trim, sorted by imaginary part then real part."""
    A, _ = model.state_matrices(model.params if params is None else params, consts)
    ev = np.linalg.eigvals(np.asarray(A))
    return ev[np.lexsort((ev.real, -ev.imag))]


def modes(eigs) -> list[dict]:
    """Each mode's kind and numbers: oscillatory modes (one per conjugate pair) give the
    natural frequency `wn` [rad/s], damping ratio `zeta`, damped frequency [Hz] and period;
    aperiodic modes give the time constant `tau = -1/lambda` (or the time to double when
    unstable)."""
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
                            period=2 * np.pi / abs(lam.imag), stable=bool(lam.real < 0)))
        else:
            re = lam.real
            out.append(dict(kind="aperiodic", eigenvalue=[re, 0.0],
                            tau=(-1.0 / re) if re != 0 else float("inf"),
                            t_double=(np.log(2) / re) if re > 0 else None,
                            stable=bool(re < 0)))
    return out
