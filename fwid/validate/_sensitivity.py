"""Sensitivities through the identification pipeline, by JAX autodiff (issue 4).

Derivatives of what the pipeline produces with respect to what goes into it:

- [`output_sensitivity`][fwid.validate.output_sensitivity]: the simulated outputs `y(t)` of
  the grey-box model (Eq. 7 integrated by RK4, Sec. IV.B) with respect to the parameters, the
  per-flight constants (trim `u0 w0 theta0`, `mass`, `Iy`, ...) or the initial state;
- [`eigenvalue_sensitivity`][fwid.validate.eigenvalue_sensitivity]: the eigenvalues of
  `A = df/dx` (Tables 3 and 6), the natural frequency and damping of the oscillatory
  (short-period-like) mode, with respect to the parameters and the constants;
  [`rank_sensitivities`][fwid.validate.rank_sensitivities] orders them by normalised
  sensitivity `(p / lambda) d lambda / d p`;
- [`metric_sensitivity`][fwid.validate.metric_sensitivity]: the gradient of the fit cost
  (Eq. 10, with R fixed or from Eq. 11) and of the per-output metrics (RMS, R^2, correlation,
  Tables 2, 5, 8) with respect to the parameters;
- [`estimate_sensitivity_to_cutoff`][fwid.validate.estimate_sensitivity_to_cutoff]: how the
  maximum-likelihood estimates move with the 5 Hz split between the cycle-averaged and the
  flapping part (Sec. III.B), by the implicit function theorem at the optimum of Eqs. 10-11.

Everything is forward mode (`jax.jacfwd`, forward-over-forward for second derivatives): the
simulation is differentiated through diffrax with `diffrax.ForwardMode`, which supports
forward mode only. All functions are pure: they read the model, the data and the fit, and
return new arrays.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg
from jaxtyping import Array, Float

from ..data._flight import Flight
from ..estimate._gauss_newton import NoiseModel, ml_cost
from ..estimate._output_error import (
    FitResult,
    _free_layout,
    _merge_batch,
    _raw_residuals,
)
from ..models._greybox import GreyBoxModel, Params
from ..simulate._experiment import Experiment
from ..simulate._simulate import simulate
from ._modes import modes

_WRT = ("params", "consts", "x0")
METRICS = ("cost", "rms", "rms_pct", "r2", "corr")


# --------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------
def _full_params(model: GreyBoxModel, params: Mapping | None) -> Params:
    """`model.params` with the entries of `params` (all or some of them) put in."""
    out = dict(model.params)
    for k, v in (params or {}).items():
        if k not in out:
            raise KeyError(f"{model.name}: no parameter '{k}' (has {', '.join(model.param_names)})")
        out[k] = jnp.asarray(v, dtype=float)
    return out


def _check_single(exp: Experiment, what: str) -> None:
    if exp.t.ndim != 1:
        raise ValueError(f"{what}: give one experiment (t of shape (n,)), not a stacked batch "
                         f"of shape {tuple(exp.t.shape)}")


def _pick_names(available: Sequence[str], names: Sequence[str] | None, what: str) -> tuple:
    if names is None:
        return tuple(available)
    names = tuple(names)
    unknown = [k for k in names if k not in available]
    if unknown:
        raise KeyError(f"unknown {what} {unknown} (has {', '.join(available)})")
    return names


# --------------------------------------------------------------------------------------
# 1. outputs
# --------------------------------------------------------------------------------------
@eqx.filter_jit
def _output_jacobian(model, exp, params, names: tuple, wrt: str):
    """`y` and `{name: dy/dname}` (each `(n, ny)`), by `jax.jacfwd` through the simulation."""

    def y_of(vals):
        if wrt == "params":
            return simulate(model, exp, {**params, **vals})[1]
        if wrt == "consts":
            e = eqx.tree_at(lambda e: e.consts, exp, {**exp.consts, **vals})
            return simulate(model, e, params)[1]
        x0 = jnp.stack([vals[k] for k in model.states])
        return simulate(model, exp, params, x0=x0)[1]

    if wrt == "params":
        vals = {k: params[k] for k in names}
    elif wrt == "consts":
        vals = {k: exp.consts[k] for k in names}
    else:
        vals = {k: exp.x0[i] for i, k in enumerate(model.states)}
    y = y_of(vals)
    S = jax.jacfwd(y_of)(vals)
    return y, {k: S[k] for k in names}


def output_sensitivity(
    model: GreyBoxModel,
    exp: Experiment,
    params: Mapping[str, float] | None = None,
    *,
    wrt: str = "params",
    names: Sequence[str] | None = None,
) -> dict[str, Float[Array, "n ny"]]:
    """Derivatives of the simulated outputs `y(t_k)` with respect to the parameters, the
    per-flight constants or the initial state.

    `y` is the output of the grey-box model (Eq. 7 for the DelFly's longitudinal dynamics)
    integrated by fixed-step RK4 at the data's sample times (Sec. IV.B), exactly what
    [`fwid.simulate`][] returns; the derivative is taken by `jax.jacfwd` through the diffrax
    solve (forward mode, one tangent per name), so it is exact to rounding: it is the
    sensitivity of the discretised simulation, not of the continuous ODE. These are the
    output sensitivities `dy/dtheta` that the Gauss-Newton steps and the Cramer-Rao bounds of
    the output-error estimator are built from.

    **Arguments:**
    - `model`: the [`fwid.GreyBoxModel`][].
    - `exp`: one [`fwid.Experiment`][] (inputs, initial state and constants).
    - `params`: parameter values to evaluate at, all or some of them (default: the model's).
    - `wrt`: `"params"` (default), `"consts"` (the experiment's constants: `mass`, `Iy`,
      `g`, the trim `u0`, `w0`, `theta0`, ...) or `"x0"` (the initial state, by state name).
    - `names`: which of them (default: the model's free parameters, all constants the
      experiment carries, or all states).

    **Returns:** `{name: dy/dname}`, each of shape `(n, ny)` (samples by outputs, in
    `model.outputs` order).

    ```python
    S = fwid.validate.output_sensitivity(model, exp)          # {"Mq": (n, 4), ...}
    S_trim = fwid.validate.output_sensitivity(model, exp, wrt="consts", names=["theta0"])
    ```
    """
    _check_single(exp, "output_sensitivity")
    if wrt not in _WRT:
        raise ValueError(f"wrt must be one of {', '.join(map(repr, _WRT))}, not {wrt!r}")
    p = _full_params(model, params)
    if wrt == "params":
        names = _pick_names(model.param_names, names if names is not None else model.free,
                            "parameters")
    elif wrt == "consts":
        names = _pick_names(tuple(exp.consts), names, "constants")
    else:
        names = _pick_names(model.states, names, "states")
    _, S = _output_jacobian(model, exp, p, names, wrt)
    return {k: S[k] for k in names}  # in the order asked for (jit returns sorted keys)


# --------------------------------------------------------------------------------------
# 2. eigenvalues
# --------------------------------------------------------------------------------------
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
    """Derivatives of the eigenvalues of `A = df/dx` and of the modes' natural frequency and
    damping with respect to the parameters and the trim/mass constants (Tables 3 and 6).

    For the DelFly's longitudinal model (Eq. 7) `A` depends on the aerodynamic derivatives
    (`Xq ... Mw`, divided by `mass` or `Iy`) and on the trim (`u0`, `w0`, `theta0`, with `g`).
    With `A v_i = lambda_i v_i` and the left eigenvectors `w_i^H A = lambda_i w_i^H`, a simple
    eigenvalue moves by

    $$\\frac{d\\lambda_i}{dp} = \\frac{w_i^H (dA/dp)\\, v_i}{w_i^H v_i},$$

    with `dA/dp` from `jax.jacfwd` of [`fwid.GreyBoxModel.state_matrices`][] (`w_i^H` are the
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
    - `sens`: the output of [`fwid.validate.eigenvalue_sensitivity`][].
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


# --------------------------------------------------------------------------------------
# 3. fit metrics
# --------------------------------------------------------------------------------------
def _metrics(y, z, mask, Rinv, logdetR):
    """The cost of Eq. 10 (R given) and the per-output metrics of `fit_metrics`, masked."""
    m = mask[:, None]
    N = jnp.sum(mask)
    ny = z.shape[-1]
    v = (z - y) * m
    cost = (0.5 * jnp.einsum("ki,ij,kj->", v, Rinv, v) + 0.5 * N * logdetR
            + 0.5 * N * ny * jnp.log(2 * jnp.pi))
    rms = jnp.sqrt(jnp.sum(v**2, axis=0) / N)
    zbar = jnp.sum(z * m, axis=0) / N
    ybar = jnp.sum(y * m, axis=0) / N
    zc, yc = (z - zbar) * m, (y - ybar) * m
    sst = jnp.sum(zc**2, axis=0)
    big, small = jnp.max(jnp.where(m > 0, z, -jnp.inf), axis=0), \
        jnp.min(jnp.where(m > 0, z, jnp.inf), axis=0)
    return dict(
        cost=cost,
        rms=rms,
        rms_pct=100.0 * rms / (big - small),
        r2=1.0 - jnp.sum(v**2, axis=0) / sst,
        corr=jnp.sum(zc * yc, axis=0) / jnp.sqrt(sst * jnp.sum(yc**2, axis=0)),
    )


@jax.jit
def _metric_gradients(y, S, z, mask, R):
    """The metrics at `y` and their derivatives along each output sensitivity in `S`."""
    if R is None:  # Eq. 11 at these parameters
        v = (z - y) * mask[:, None]
        R = v.T @ v / jnp.sum(mask)
    Rinv = jnp.linalg.inv(R)
    logdet = jnp.linalg.slogdet(R)[1]

    def f(yy):
        return _metrics(yy, z, mask, Rinv, logdet)

    grad = {k: jax.jvp(f, (y,), (s,))[1] for k, s in S.items()}
    return f(y), grad, R


def metric_sensitivity(
    model: GreyBoxModel,
    exp: Experiment,
    params: Mapping[str, float] | None = None,
    *,
    R: Float[Array, "ny ny"] | None = None,
    names: Sequence[str] | None = None,
) -> dict:
    """Gradients of the fit cost (Eq. 10) and of the per-output fit metrics with respect to
    the parameters.

    The cost is the output-error negative log-likelihood of Eq. (10),

    $$J(\\theta) = \\frac12 \\sum_k v_k^T R^{-1} v_k + \\frac{N}{2}\\ln\\det R
    + \\frac{N n_y}{2}\\ln 2\\pi, \\qquad v_k = z_k - y_k(\\theta),$$

    with `R` held fixed, so `dJ/dtheta = -sum_k (dy_k/dtheta)^T R^{-1} v_k`. Without `R`, R is
    Eq. (11) at `params`; then `J` equals the concentrated cost `N/2 ln det R(theta) + const`
    that [`fwid.fit`][] reports, and (R being its minimiser) so does the gradient: it is zero
    at a converged estimate. The per-output metrics are those of
    [`fwid.validate.fit_metrics`][] (Tables 2, 5, 8): `rms`, `rms_pct`, `r2`, `corr`
    (computed over the experiment's unmasked samples). All derivatives are exact (forward
    mode through the simulation, then the chain rule).

    **Arguments:**
    - `model`, `exp`: the model and one [`fwid.Experiment`][].
    - `params`: where to evaluate (default: the model's values).
    - `R`: the noise covariance to hold fixed, e.g. a [`fwid.FitResult`][]'s `R`.
    - `names`: the parameters to differentiate with respect to (default: the free ones).

    **Returns:** `{metric: {"value": ..., "grad": {name: ...}}}` for `metric` in `"cost"`
    (scalars) and `"rms"`, `"rms_pct"`, `"r2"`, `"corr"` (arrays `(ny,)`, by output), plus
    `"outputs"` (the output names) and `"R"` (the covariance used).
    """
    _check_single(exp, "metric_sensitivity")
    p = _full_params(model, params)
    names = _pick_names(model.param_names, names if names is not None else model.free,
                        "parameters")
    Rj = None if R is None else jnp.asarray(R, dtype=float)
    y, S = _output_jacobian(model, exp, p, names, "params")  # shared with output_sensitivity
    value, grad, R_used = _metric_gradients(y, S, exp.z, exp.mask, Rj)
    out: dict = {k: {"value": value[k], "grad": {n: grad[n][k] for n in names}}
                 for k in METRICS}
    out["outputs"] = model.outputs
    out["R"] = R_used
    return out


# --------------------------------------------------------------------------------------
# 4. estimates vs the split cut-off
# --------------------------------------------------------------------------------------
def _stack_traced(exps: Sequence[Experiment]) -> Experiment:
    """[`fwid.stack_experiments`][] in jnp: pads (hold the last value, mask 0) and stacks,
    so the experiments may depend on traced values (the cut-off). Forces are left out."""
    n = max(e.n for e in exps)

    def pad(e: Experiment) -> Experiment:
        k = n - e.n
        dt = e.t[1] - e.t[0]

        def hold(a):
            return jnp.concatenate([a, jnp.repeat(a[-1:], k, 0)], 0)

        return Experiment(jnp.concatenate([e.t, e.t[-1] + dt * jnp.arange(1, k + 1)]),
                          hold(e.u), hold(e.z), e.x0, e.consts,
                          jnp.concatenate([e.mask, jnp.zeros(k)]))

    return jax.tree.map(lambda *a: jnp.stack(a), *[pad(e) for e in exps])


def _cutoff_setup(model, flight, fit_result, noise):
    flights = [flight] if isinstance(flight, Flight) else list(flight)
    # numpy-backed copies: their time step, trim and vehicle stay concrete inside `jax.jit`
    flights = [jax.tree.map(np.asarray, f) for f in flights]
    if noise not in ("relaxed", "fixed"):
        raise ValueError(f"noise must be 'relaxed' or 'fixed', not {noise!r}")
    names = tuple(fit_result.names)
    n_local = len(flights) if (len(flights) > 1 and any("@" in k for k in names)) else 0
    layout = tuple(_free_layout(model, n_local)[2])
    if layout != names:
        raise ValueError(f"the fit's parameters {names} are not those of fitting "
                         f"{model.name!r} to {len(flights)} flight(s): {layout}")
    base = model.with_params({k: fit_result.model.params[k] for k in model.param_names})
    return flights, names, n_local, base


def cutoff_cost(
    model: GreyBoxModel,
    flight: Flight | Sequence[Flight],
    fit_result: FitResult,
    *,
    noise: str = "relaxed",
    noise_cutoff: float | None = 40.0,
    edge: float = 0.2,
) -> Callable[[Float[Array, " p"], Float[Array, ""]], Float[Array, ""]]:
    """The output-error cost as a pure function `L(theta, cutoff)` of the free parameters and
    the split cut-off: inside it the flights are cycle-averaged at `cutoff`
    ([`fwid.cycle_averaged`][]) and cut to [`fwid.Experiment`][]s as [`fwid.identify`][] does.

    - `noise="relaxed"`: Eq. (10) with R from Eq. (11) at `theta` (plus [`fwid.fit`][]'s tiny
      floor), i.e. `N/2 ln det R(theta, cutoff) + const`, whose stationary point is what
      [`fwid.fit`][]'s relaxation converges to;
    - `noise="fixed"`: the data term of Eq. (10) with R held at `fit_result.R`,
      `1/2 sum_k v_k^T R^-1 v_k`.

    `theta` is laid out as `fit_result.theta` (`fit_result.names`); the parameters that were
    not estimated keep `fit_result.model`'s values. Jit-able, and differentiable in both
    arguments in forward mode (`jax.jacfwd`; reverse mode does not go through the diffrax
    simulation). Arguments as [`fwid.validate.estimate_sensitivity_to_cutoff`][].
    """
    flights, _, n_local, base = _cutoff_setup(model, flight, fit_result, noise)
    R = np.asarray(fit_result.R)
    diagonal = bool(np.all(R[~np.eye(R.shape[0], dtype=bool)] == 0))
    Rinv = jnp.asarray(np.linalg.inv(R)) if noise == "fixed" else None
    from .._identify import averaged  # noqa: PLC0415  (fwid._identify imports fwid.validate)

    def L(theta, cutoff):
        batch = _stack_traced([averaged(f, base, cutoff, noise_cutoff, edge) for f in flights])
        v = _raw_residuals(base, _merge_batch(base, theta, n_local), batch)
        if Rinv is not None:
            return 0.5 * jnp.einsum("...i,ij,...j->", v, Rinv, v)
        noise = NoiseModel.of_data(batch.z, batch.mask, diagonal)  # as fwid.fit
        return ml_cost(noise.R(v), noise.N, batch.z.shape[-1])

    return L


def estimate_sensitivity_to_cutoff(
    model: GreyBoxModel,
    flight: Flight | Sequence[Flight],
    fit_result: FitResult,
    cutoff: float = 5.0,
    *,
    noise: str = "relaxed",
    noise_cutoff: float | None = 40.0,
    edge: float = 0.2,
) -> dict:
    """How the output-error estimates move with the split cut-off (5 Hz, Sec. III.B):
    `d theta_hat / d cutoff` by the implicit function theorem.

    The estimate is a stationary point of the cost, `g(theta, c) = dL/dtheta = 0`, where the
    data (the cycle-averaged outputs `z`, inputs `u` and initial state `x0`) depend on the
    cut-off `c` through the zero-phase split ([`fwid.cycle_averaged`][], differentiable in
    `c`), exactly as [`fwid.identify`][] builds them (0.2 s dropped at each end). Then

    $$\\frac{d\\hat\\theta}{dc} = -\\Big(\\frac{\\partial g}{\\partial\\theta}\\Big)^{-1}
    \\frac{\\partial g}{\\partial c},$$

    with the full Hessian `dg/dtheta` (second derivatives of the simulation included, not the
    Gauss-Newton approximation) and `dg/dc`, both by forward-over-forward autodiff through the
    filter and the diffrax simulation of [`fwid.validate.cutoff_cost`][]'s `L`:

    - `noise="relaxed"` (default): Eq. (10) with R from Eq. (11), the cost whose minimum
      [`fwid.fit`][]'s relaxation converges to: the result is the derivative of what
      [`fwid.fit`][] returns at a nearby cut-off;
    - `noise="fixed"`: Eq. (10) with R held at `fit_result.R`. This leaves out the change of
      R with the data, which is not small: the noise the split lets through moves with the
      cut-off, and with it the weights of the outputs. On the embedded DelFly flights the two
      differ by a factor of order one.

    The derivative is local: on the embedded flights `theta_hat(c)` curves on a scale of a
    few tenths of a Hz (a central difference with a 0.05 Hz step is already off by ~1 %), so
    compare refits over 4-6 Hz with the linear prediction only as a trend.

    The fit must have converged: the result is evaluated at `fit_result.theta`;
    `"newton_step"` (the Newton step `-H^{-1} g` there) shows how far that is from the exact
    optimum (~1e-7 relative after [`fwid.fit`][]).

    **Arguments:**
    - `model`: the model that was fitted (its non-free parameters are taken from
      `fit_result.model`).
    - `flight`: the raw (not cycle-averaged) [`fwid.Flight`][], or the flights of a joint fit
      in the order they were fitted.
    - `fit_result`: the [`fwid.FitResult`][] of fitting `model` to the flight(s)' cycle-averaged
      part at `cutoff` (e.g. `Identification.fit`).
    - `cutoff`: the split cut-off [Hz] the fit used.
    - `noise`: `"relaxed"` or `"fixed"`, see above.
    - `noise_cutoff`, `edge`: as in [`fwid.identify`][] (40 Hz, 0.2 s).

    **Returns:** a dict with `"names"` (as `fit_result.names`), `"theta"`, `"d_theta"`
    (`(p,)`, units per Hz), `"by_name"` (`{name: d theta / d cutoff}`), `"relative"`
    (`{name: (1 / theta) d theta / d cutoff}`, per Hz), `"newton_step"` (`(p,)`),
    `"hessian"` (`dg/dtheta`, `(p, p)`), `"d_gradient_d_cutoff"` (`dg/dc`, `(p,)`),
    `"cutoff"` and `"noise"`.
    """
    names = _cutoff_setup(model, flight, fit_result, noise)[1]
    L = cutoff_cost(model, flight, fit_result, noise=noise, noise_cutoff=noise_cutoff, edge=edge)

    def g(theta, c):
        gr = jax.jacfwd(L, argnums=0)(theta, c)
        return gr, gr

    @jax.jit
    def derivatives(theta, c):
        (H, gc), gr = jax.jacfwd(g, argnums=(0, 1), has_aux=True)(theta, c)
        return H, gc, gr

    theta = jnp.asarray(fit_result.theta)
    H, gc, gr = (np.asarray(a) for a in derivatives(theta, jnp.asarray(cutoff, dtype=float)))
    H = 0.5 * (H + H.T)
    D = 1.0 / np.sqrt(np.abs(np.diag(H)))
    Hs = D[:, None] * H * D[None, :]
    dtheta = -D * np.linalg.solve(Hs, D * gc)
    step = -D * np.linalg.solve(Hs, D * gr)
    th = np.asarray(theta)
    return {
        "names": names,
        "theta": th,
        "d_theta": dtheta,
        "by_name": dict(zip(names, dtheta.tolist())),
        "relative": {k: (d / t if t != 0 else float("nan"))
                     for k, d, t in zip(names, dtheta.tolist(), th.tolist())},
        "newton_step": step,
        "hessian": H,
        "d_gradient_d_cutoff": gc,
        "cutoff": float(cutoff),
        "noise": noise,
    }
