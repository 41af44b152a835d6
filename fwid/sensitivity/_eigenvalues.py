"""Derivatives of the eigenvalues of `A = df/dx` (Tables 3 and 6) and of the modes (natural
frequency, damping, time constants) with respect to the parameters and the constants, and
their ranking by normalised sensitivity."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg

from ..models._greybox import GreyBoxModel
from ..validate._modes import modes
from ._common import _full_params, _pick_names


@eqx.filter_jit
def _state_matrix_jacobian(model, params, consts):
    def A_of(p, c):
        return model.state_matrices(p, c)[0]

    return A_of(params, consts), jax.jacfwd(A_of, argnums=(0, 1))(params, consts)


def _ordered(ev):
    """The permutation of [`fwid.validate.eigenvalues`][]: by imaginary part, then real."""
    return np.lexsort((ev.real, -ev.imag))


def eigenvalue_sensitivity(
    model: GreyBoxModel,
    consts: Mapping[str, float],
    params: Mapping[str, float] | None = None,
    *,
    names: Sequence[str] | None = None,
) -> dict:
    """Derivatives of the eigenvalues and modes with respect to parameters and constants.

    The eigenvalues of `A = df/dx` and the modes' natural frequency and damping (Tables 3
    and 6), differentiated with respect to the parameters and the trim/mass constants.

    For the DelFly's longitudinal model (Eq. 7) `A` depends on the aerodynamic derivatives
    (`Xq ... Mw`, divided by `mass` or `Iy`) and on the trim (`u0`, `w0`, `theta0`, with `g`).
    With `A v_i = lambda_i v_i` and the left eigenvectors `w_i^H A = lambda_i w_i^H`, a simple
    eigenvalue moves by

    $$\\frac{d\\lambda_i}{dp} = \\frac{w_i^H (dA/dp)\\, v_i}{w_i^H v_i},$$

    with `dA/dp` from `jax.jacfwd` of `state_matrices` of [`fwid.GreyBoxModel`][] (`w_i^H` are the
    rows of `V^{-1}`). For an oscillatory pair with `lambda = -zeta wn + i wn sqrt(1 - zeta^2)`:
    `d wn = Re(conj(lambda) d lambda) / wn` and `d zeta = -(d Re lambda) / wn - Re(lambda)
    d wn / wn^2`; for an aperiodic mode `d tau = d lambda / lambda^2` (`tau = -1/lambda`). The
    formula holds for simple (distinct) eigenvalues; at a repeated one (the point where two
    real poles meet and turn into a pair) the derivative does not exist.

    **Arguments:**
    - `model`: the [`fwid.GreyBoxModel`][].
    - `consts`: the constants the model reads (mass, inertia, trim), e.g.
      `Identification.consts` or `exp.consts`.
    - `params`: parameter values to evaluate at, all or some (default: the model's).
    - `names`: the parameters and constants to differentiate with respect to (default: the
      model's free parameters, then every constant given).

    **Returns:** a dict with
    - `"eigenvalues"`: complex `(nx,)`, ordered as [`fwid.validate.eigenvalues`][];
    - `"names"`: the names differentiated with respect to; `"values"`: their values;
    - `"d_eigenvalues"`: `{name: complex (nx,)}`, `d lambda_i / d name`; `"d_real"`,
      `"d_imag"`: the same split into real and imaginary parts (float arrays);
    - `"modes"`: [`fwid.validate.modes`][]'s list (one entry per mode), each entry extended
      with `"index"` (its eigenvalue's position; the one with positive imaginary part for a
      pair), `"d_eigenvalue"` (`{name: complex}`), and `"d_wn"`, `"d_zeta"` (oscillatory) or
      `"d_tau"` (aperiodic), each `{name: float}`;
    - `"short_period"`: the position in `"modes"` of the oscillatory mode with the highest
      natural frequency (the DelFly's short-period-like mode, Sec. IV.C), or `None`.
    """
    p = _full_params(model, params)
    c = {k: jnp.asarray(v, dtype=float) for k, v in consts.items()}
    missing = [k for k in model.constants if k not in c]
    if missing:
        raise KeyError(f"{model.name}: constants {missing} are missing from `consts`")
    default = tuple(model.free) + tuple(k for k in c if k not in model.free)
    names = _pick_names(tuple(model.param_names) + tuple(k for k in c if k not in p),
                        names if names is not None else default, "parameters or constants")
    A, (dA_p, dA_c) = _state_matrix_jacobian(model, p, c)
    A = np.asarray(A)
    lam, V = scipy.linalg.eig(A)
    Winv = np.linalg.inv(V)  # rows: left eigenvectors with w_i^H v_i = 1
    order = _ordered(lam)
    lam, V, Winv = lam[order], V[:, order], Winv[order, :]
    d = {}
    for k in names:
        dA = np.asarray(dA_p[k] if k in dA_p else dA_c[k])
        d[k] = np.einsum("ij,jk,ki->i", Winv, dA, V)
    values = {k: float(p[k]) if k in p else float(c[k]) for k in names}
    out_modes = []
    short, best = None, -np.inf
    for m in modes(lam):
        m = dict(m)
        target = m["eigenvalue"][0] + 1j * m["eigenvalue"][1]
        i = int(np.argmin(np.abs(lam - target)))
        li = lam[i]
        m["index"] = i
        m["d_eigenvalue"] = {k: complex(d[k][i]) for k in names}
        if m["kind"] == "oscillatory":
            wn = abs(li)
            dwn = {k: float(np.real(np.conj(li) * d[k][i]) / wn) for k in names}
            m["d_wn"] = dwn
            m["d_zeta"] = {k: float(-np.real(d[k][i]) / wn + li.real * dwn[k] / wn**2)
                           for k in names}
            if wn > best:
                short, best = len(out_modes), wn
        else:
            m["d_tau"] = {k: float(np.real(d[k][i]) / li.real**2) if li.real != 0
                          else float("nan") for k in names}
        out_modes.append(m)
    return {
        "eigenvalues": lam,
        "names": names,
        "values": values,
        "d_eigenvalues": d,
        "d_real": {k: np.real(v) for k, v in d.items()},
        "d_imag": {k: np.imag(v) for k, v in d.items()},
        "modes": out_modes,
        "short_period": short,
    }


_QUANTITIES = ("eigenvalue", "real", "imag", "wn", "zeta", "tau")


def rank_sensitivities(
    sens: dict,
    *,
    mode: int | str = "short-period",
    quantity: str = "eigenvalue",
    names: Sequence[str] | None = None,
) -> list[tuple[str, float]]:
    """Rank parameters (and constants) by the normalised sensitivity of one mode.

    The normalised (logarithmic) sensitivity `(p / q) dq / dp` is the relative change of the
    mode's quantity `q` per relative change of `p`: 0.5 means a 1 % larger `p` moves `q` by
    0.5 %, whatever their units, so aerodynamic derivatives, masses and trim angles compare
    directly.

    **Arguments:**
    - `sens`: the output of [`fwid.eigenvalue_sensitivity`][].
    - `mode`: `"short-period"` (the oscillatory mode of highest natural frequency, the one
      Sec. IV.C likens to the short period) or an index into `sens["modes"]`.
    - `quantity`: `"eigenvalue"` (`|p d lambda/dp| / |lambda|`, the modulus of the complex
      normalised sensitivity, `>= 0`), `"real"`, `"imag"` (of the eigenvalue with positive
      imaginary part), `"wn"`, `"zeta"` (oscillatory modes) or `"tau"` (aperiodic modes);
      the last five are signed.
    - `names`: restrict to these (default: all in `sens["names"]`).

    **Returns:** `[(name, normalised sensitivity), ...]`, largest magnitude first.
    """
    if quantity not in _QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(_QUANTITIES)}, not {quantity!r}")
    if mode == "short-period":
        mode = sens["short_period"]
        if mode is None:
            raise ValueError("the model has no oscillatory mode to call short period")
    m = sens["modes"][int(mode)]
    lam = sens["eigenvalues"][m["index"]]
    names = _pick_names(sens["names"], names, "names")
    out = []
    for k in names:
        p = sens["values"][k]
        dl = m["d_eigenvalue"][k]
        if quantity == "eigenvalue":
            v = abs(p * dl) / abs(lam)
        elif quantity == "real":
            v = p * dl.real / lam.real
        elif quantity == "imag":
            v = p * dl.imag / lam.imag if lam.imag != 0 else float("nan")
        elif quantity in ("wn", "zeta", "tau"):
            key = "d_" + quantity
            if key not in m:
                raise ValueError(f"mode {mode} is {m['kind']}: it has no {quantity!r}")
            v = p * m[key][k] / m[quantity]
        out.append((k, float(v)))
    return sorted(out, key=lambda kv: -abs(kv[1]) if np.isfinite(kv[1]) else 0.0)
