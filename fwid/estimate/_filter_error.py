"""The filter-error method (Jategaonkar 2015, Ch. 5): maximum likelihood with process noise.

Output error (Eqs. 10-11) assumes that the model's simulation is the true state: turbulence
and the vehicle's own wake (process noise) then colour the residuals and bias the estimates.
The filter-error method puts a Kalman filter inside the likelihood: the residuals are the
filter's innovations (Eqs. 5.45-5.47, predictor-corrector, the prediction by RK4 as the
simulation)

    y_k = h(x~_k, u_k),   nu_k = z_k - y_k,   x^_k = x~_k + K nu_k,
    x~_{k+1} = x^_k + int f(x, u) dt,

with the steady-state gain of the model linearised at the experiment's initial state and
first input (Eqs. 5.50-5.51; exact for a linear model), `P` from the Riccati equation of
`fwid.estimate._riccati` with the process-noise distribution matrix `F` (diagonal, one entry
per state, estimated with the parameters). The gain is the book's `K = P C^T R^-1` (Eq.
5.48). Where the process noise over a sample outweighs the innovations (`F^2 dt > R`:
accurate cycle-averaged data of an unstable vehicle), that gain exceeds one, over-corrects
every sample and the relaxation does not settle; where it does not, the fit is run again
with the discrete corrector's gain `K = P C^T (C P C^T + R)^-1`, the book's to first order in
`P / R` and never beyond one, and kept if it converges (`FilterErrorResult.gain` says which
gain the estimates come from; `gain=` chooses one).

The start (with `start="least-squares"`, for a model whose states are measured) is the
equation-error estimate and its residual covariance (`fwid.estimate._equation_error`): the
parameters, `F` from the covariance `Q` of its state equations' residuals as white process
noise over a sample (`F_i = sqrt(Q_ii dt)`), and the first `R` of the gain from the
one-sample-ahead prediction errors of the outputs from the measured states: what an
unstable vehicle flown in closed loop needs, whose open-loop simulation (the book's start
of `R`) runs away. The cost is the
negative log-likelihood `1/2 sum nu^T R^-1 nu + N/2 ln det R` (Eq. 5.36) with the innovation
covariance `R` estimated explicitly (Eq. 5.40, diagonal as the book by default).

The minimisation is the book's relaxation (Sec. 5.6): for the `R` that the gain uses, the
parameters and `F` by Gauss-Newton ([`RelaxedGaussNewton`][], the weighting `R` relaxed at
every step as in output error); then that `R` is replaced by the new estimate and `F`
compensated for the change (the heuristic of Eq. 5.41); repeated until `R` settles. Unlike
the book's software (finite differences, perturbed gain matrices), the Jacobians of the
innovations come from forward-mode autodiff through the filter, the matrix exponential and
the Riccati solution (implicit function theorem).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._advice import advise
from .._errors import FitDivergedError
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment, stack_experiments
from ._equation_error import equation_error_start, measured_state_index
from ._gauss_newton import NoiseModel, noise_covariance, solve_relaxed
from ._noise import check_noise
from ._problem import FitResult, flight_params, free_layout, merge_batch, prepare
from ._riccati import steady_state_gain
from ._steps import rk4_step
from ._uncertainty import correlation, covariance_held, lag1_autocorrelation
from ._warnings import fit_warnings, issue

#: Lags of the innovations' autocorrelation that the whiteness measure looks at.
_DEBUG = False  # print every relaxation pass (for development)
WHITENESS_LAGS = 20
#: Innovations are called white when at most this fraction of the lags falls outside the
#: 95 % band (5 % fall outside by chance).
WHITENESS_OUTSIDE_MAX = 0.1


class FilterErrorResult(FitResult):
    """A [`fwid.FitResult`][] of the filter-error method, with the filter's quantities.

    **Extra fields:**
    - `F`: the diagonal of the process-noise distribution matrix (also in `theta` as
      `F_<state>`).
    - `K`: the steady-state Kalman gain (of the first experiment); `P` its prediction
      covariance.
    - `innovations`: the innovations `(experiments, n, ny)` (zero on padding).
    - `whiteness`: per output, the share of the innovations' autocorrelations at lags
      1..[`WHITENESS_LAGS`][] outside the 95 % band `+-1.96/sqrt(N)`, the largest one, and
      `"white"` (at most [`WHITENESS_OUTSIDE_MAX`][] outside); see [`whiteness`][].
    - `outer`: the relaxation passes (R updates with F compensation).
    - `gain`: the gain used, `"book"` (Eq. 5.48) or `"bounded"` (see the module docstring).
    """

    F: Float[Array, " nx"] | None = None
    K: Float[Array, "nx ny"] | None = None
    P: Float[Array, "nx nx"] | None = None
    innovations: Float[Array, "b n ny"] | None = None
    whiteness: dict | None = eqx.field(static=True, default=None)
    outer: int = eqx.field(static=True, default=0)
    gain: str = eqx.field(static=True, default="book")

    @property
    def white(self) -> bool:
        """Whether every output's innovations are white (see `whiteness`)."""
        return all(w["white"] for w in (self.whiteness or {}).values())


def whiteness(nu, mask, outputs: Sequence[str], lags: int = WHITENESS_LAGS) -> dict:
    """The whiteness of innovations `nu` `(b, n, ny)` (padding masked by `mask` `(b, n)`):
    per output the normalised autocorrelation at lags 1..`lags` (within each experiment,
    pooled), the share outside the 95 % band `+-1.96/sqrt(N)` and whether that share is at
    most [`WHITENESS_OUTSIDE_MAX`][] (for white innovations about 5 % fall outside)."""
    nu = np.asarray(nu) * np.asarray(mask)[..., None]
    N = float(np.sum(mask))
    band = 1.96 / float(np.sqrt(N))  # (a Python float: numpy scalars in a static field warn)
    out = {}
    for j, name in enumerate(outputs):
        x = nu[..., j] - np.sum(nu[..., j]) / N * np.asarray(mask)
        c0 = np.sum(x * x)
        r = np.array([np.sum(x[:, :-k] * x[:, k:]) for k in range(1, lags + 1)]) / c0
        outside = float(np.mean(np.abs(r) > band))
        out[name] = {"outside_pct": 100 * outside, "max_abs": float(np.max(np.abs(r))),
                     "band": band, "white": outside <= WHITENESS_OUTSIDE_MAX}
    return out


def _filter(model: GreyBoxModel, params, fdiag, Rk, e: Experiment, gain: str = "book"):
    """The innovations of one experiment (Eqs. 5.45-5.47) and the filter's `K`, `P`, `C`;
    `gain`: `"book"` (Eq. 5.48), `"bounded"` (the discrete corrector's) or `"none"` (`K = 0`:
    the output-error residuals)."""
    u0 = e.u[0]
    A = jax.jacfwd(model.f, argnums=0)(e.x0, u0, params, e.consts)  # Eq. (5.50)
    C = jax.jacfwd(model.h, argnums=0)(e.x0, u0, params, e.consts)  # Eq. (5.51)
    dt = e.t[1] - e.t[0]
    K, P = steady_state_gain(A, C, jnp.diag(fdiag**2), Rk, dt)
    if gain == "bounded":  # see the module docstring
        K = jnp.linalg.solve(C @ P @ C.T + Rk, C @ P).T
    if gain == "none":
        K, P = jnp.zeros_like(K), jnp.zeros_like(P)
    u_next = jnp.concatenate([e.u[1:], e.u[-1:]], axis=0)

    def step(x, data):
        uk, uk1, zk, mk = data
        nu = (zk - model.h(x, uk, params, e.consts)) * mk
        xh = x + K @ nu  # Eq. (5.47)
        return rk4_step(model.f, xh, uk, uk1, dt, params, e.consts), nu

    _, nus = jax.lax.scan(step, e.x0, (e.u, u_next, e.z, e.mask))
    return nus, K, P, C


def _innovations(model, theta, Rk, batch, p, gain="book", n_local=0):
    """The innovations of every experiment of `batch` (`theta`: the free parameters, with
    `n_local` values of each local one, one per experiment, when `n_local > 0`, then F)."""
    if n_local == 0:
        params = model.merge(theta[:p])
        return jax.vmap(lambda e: _filter(model, params, theta[p:], Rk, e, gain))(batch)
    merged = merge_batch(model, theta[:p], n_local)
    return jax.vmap(lambda e, b: _filter(model, flight_params(merged, b), theta[p:], Rk, e,
                                         gain))(batch, jnp.arange(n_local))


@eqx.filter_jit
def _inner(model, theta0, batch, Rk, *, p, diagonal, max_steps, rtol, cost_rtol, n_local=0,
           gain="book"):
    """Gauss-Newton on the parameters and F for the gain's innovation covariance `Rk`."""
    noise = NoiseModel.of_data(batch.z, batch.mask, diagonal)

    def residuals_and_jacobian(theta):
        def nus(th):
            return _innovations(model, th, Rk, batch, p, gain, n_local=n_local)[0]
        # one trace of the filter for the innovations and their Jacobian
        eye = jnp.eye(theta.shape[0], dtype=theta.dtype)
        return jax.vmap(lambda t: jax.jvp(nus, (theta,), (t,)), out_axes=(None, -1))(eye)

    sol = solve_relaxed(residuals_and_jacobian, theta0, noise, rtol=rtol, cost_rtol=cost_rtol,
                        max_steps=max_steps)
    _, K, P, C = _innovations(model, sol.theta, Rk, batch, p, gain, n_local=n_local)
    Sw = sol.whitened()[1].reshape(-1, sol.theta.shape[0])
    return dict(theta=sol.theta, R=sol.R, v=sol.v, M=Sw.T @ Sw, cost=sol.cost,
                steps=sol.steps, accepted=sol.accepted, converged=sol.converged, K=K[0],
                P=P[0], C=C[0], hist=sol.history)


@eqx.filter_jit
def _output_error_r(model, theta, batch, p, diagonal, n_local=0):
    """R (Eq. 11) of the residuals with `K = 0` (F = 0): the book's initial R (Sec. 5.6)."""
    v = _innovations(model, theta, jnp.eye(batch.z.shape[-1]), batch, p, gain="none",
                     n_local=n_local)[0]
    return noise_covariance(v, jnp.sum(batch.mask), diagonal, jnp.zeros(v.shape[-1]))


def _one_step_r(model: GreyBoxModel, exps: Sequence[Experiment], diagonal: bool):
    """The covariance of the outputs' one-sample-ahead prediction errors from the measured
    states (one RK4 step of the model from each measured state): the innovations of a filter
    that trusts the measurements, the start of `R` from an equation-error estimate."""
    idx = measured_state_index(model)
    nus = []
    for e in exps:
        x = e.z[:, idx]

        def one(xk, uk, uk1, p=model.params, c=e.consts, dt=e.dt):
            return model.h(rk4_step(model.f, xk, uk, uk1, dt, p, c), uk1, p, c)

        y = jax.vmap(one)(x[:-1], e.u[:-1], e.u[1:])
        nus.append(np.asarray(e.z[1:] - y))
    nu = np.concatenate(nus)
    R = nu.T @ nu / len(nu)
    return jnp.asarray(np.diag(np.diag(R)) if diagonal else R)


def compensate_f(fdiag, C, R_old, R_new):
    """Eq. (5.41): the F entries scaled for the change of R, so that the gain stays about the
    same: `f_i *= sum_j C_ji^2 r_j^-1 sqrt(r_j,new / r_j) / sum_j C_ji^2 r_j^-1` with `r_j`
    the diagonal of the old R."""
    ri = 1.0 / np.diag(np.asarray(R_old))
    ratio = np.sqrt(np.diag(np.asarray(R_new)) / np.diag(np.asarray(R_old)))
    C2 = np.asarray(C) ** 2
    den = C2.T @ ri
    factor = np.where(den > 0, (C2.T @ (ri * ratio)) / np.where(den > 0, den, 1.0), 1.0)
    # (never more than doubled in one pass; Gauss-Newton does the rest)
    return np.asarray(fdiag) * np.clip(np.nan_to_num(factor, nan=1.0), 0.0, 2.0)


def _default_f(model: GreyBoxModel, exps: Sequence[Experiment]) -> np.ndarray:
    """Start values of F: 1 % of the RMS rate of change of each state that is measured (an
    output), per square root of a second; 1e-3 for the others."""
    out = []
    for i, s in enumerate(model.states):
        if s in model.outputs:
            j = model.outputs.index(s)
            d = np.concatenate([np.diff(np.asarray(e.z)[:, j]) / float(e.dt) for e in exps])
            out.append(0.01 * float(np.sqrt(np.mean(d**2))) + 1e-9)
        else:
            out.append(1e-3)
    return np.array(out)


def fit_filter_error(
    model: GreyBoxModel,
    exps: Sequence[Experiment],
    *,
    names: Sequence[str],
    start="least-squares",
    noise: str = "auto",
    max_steps: int = 60,
    rtol: float = 1e-10,
    cost_rtol: float = 1e-10,
    progress: bool = False,
    process_noise: Sequence[float] | None = None,
    max_outer: int = 60,
    outer_rtol: float = 1e-4,
    steps_per_pass: int = 4,
    local_per_flight: bool = False,
    gain: str = "auto",
) -> FilterErrorResult:
    """[`fwid.fit`][] with `method="filter-error"` (see the module docstring).

    **Options:**
    - `process_noise`: start values of the diagonal of F, one per state (default: from the
      equation-error start, see the module docstring; where the states are not measured, 1 %
      of each measured state's RMS rate, see `_default_f`).
    - `max_outer`, `outer_rtol`, `steps_per_pass`: relaxation passes, each
      `steps_per_pass` Gauss-Newton steps and then the R of the gain updated and F
      compensated, until the diagonal of R changes by less than `outer_rtol` (relative; the
      book's `tolR`). `max_steps` is not used (at most `max_outer * steps_per_pass` steps).
    `noise`: `"auto"` and `"diagonal"` use a diagonal R (as the book), `"full"` a full one.
    - `local_per_flight`: with several experiments, estimate the model's `local` parameters
      (bias terms) per experiment (named `name@i`, as output error's joint fits); by default
      they are shared between the experiments.
    - `gain`: `"book"` (Eq. 5.48), `"bounded"` (the discrete corrector's) or `"auto"`: the
      book's, and the bounded one where the book's does not converge (module docstring).

    **Returns:** a [`FilterErrorResult`][]; its `names` are the model's free parameters and
    then `F_<state>`.
    """
    check_noise(noise)
    diagonal = noise != "full"
    t0 = time.perf_counter()
    n_local = len(exps) if (local_per_flight and len(exps) > 1 and model.local) else 0
    start, ee = equation_error_start(model, exps, names, start)
    start_model, theta0 = prepare(model, list(exps), list(names), start, n_local)
    p = theta0.shape[0]
    if process_noise is not None:
        f0 = process_noise
    elif ee is not None:
        f0 = np.sqrt(np.clip(np.diag(np.asarray(ee.R)), 0, None) * float(exps[0].dt)) + 1e-12
    else:
        f0 = _default_f(model, exps)
    f0 = np.asarray(f0, dtype=float)
    if f0.shape != (len(model.states),):
        raise ValueError(f"process_noise: one value per state ({', '.join(model.states)}), "
                         f"not {f0.shape}")
    batch = stack_experiments(list(exps))
    theta = jnp.concatenate([theta0, jnp.asarray(f0)])
    Rk = (_one_step_r(start_model, exps, diagonal) if ee is not None
          else _output_error_r(start_model, theta, batch, p, diagonal, n_local))
    if not bool(jnp.all(jnp.isfinite(Rk))):
        Rk = jnp.diag(jnp.var(batch.z.reshape(-1, batch.z.shape[-1]), axis=0))
    if gain not in ("auto", "book", "bounded"):
        raise ValueError(f"gain must be 'auto', 'book' or 'bounded', not {gain!r}")
    if progress:
        print(f"fwid: fitting {model.name} by filter error to {', '.join(names)} ...",
              flush=True)
    run = dict(model=model, start_model=start_model, theta=theta, Rk=Rk, batch=batch, p=p,
               n_local=n_local, names=names, diagonal=diagonal, max_outer=max_outer,
               outer_rtol=outer_rtol, steps_per_pass=steps_per_pass, rtol=rtol,
               cost_rtol=cost_rtol, max_steps=max_steps)
    # with "auto", the book's gain; where its relaxation does not settle, the bounded one,
    # kept if it converges (or if the book's raised)
    gains = ("book", "bounded") if gain == "auto" else (gain,)
    res = None
    for g in gains:
        try:
            tried = _relax(gain=g, **run)
        except FitDivergedError:
            if res is None and g == gains[-1]:
                raise
            continue
        if res is None or bool(tried.converged):
            res = tried
        if bool(res.converged):
            break
    issue(res.warnings, stacklevel=4)
    if progress:
        print(f"fwid: filter error {'converged' if bool(res.converged) else 'NOT converged'} "
              f"in {res.outer} relaxation passes, {int(res.steps)} Gauss-Newton steps"
              f"{' (the bounded gain)' if res.gain == 'bounded' else ''}, "
              f"{time.perf_counter() - t0:.1f} s", flush=True)
    return res


def _relax(*, model, start_model, theta, Rk, batch, p, n_local, names, diagonal, max_outer,
           outer_rtol, steps_per_pass, rtol, cost_rtol, max_steps, gain):
    """The book's relaxation (Sec. 5.6) from `theta` (parameters, then F) and the gain's
    `Rk`, with the gain `gain`: the [`FilterErrorResult`][] with its warnings."""
    start = theta
    steps, last, change, moved = 0, None, float("nan"), 0
    rise_max = 0.01 * float(jnp.sum(batch.mask)) * batch.z.shape[-1]
    halvings, alt = 0, None  # F-compensation halvings; (theta, Rk) before the compensation
    for outer in range(1, max_outer + 1):
        out = _inner(start_model, theta, batch, Rk, p=p, diagonal=diagonal,
                     max_steps=steps_per_pass, rtol=rtol, cost_rtol=cost_rtol, n_local=n_local,
                     gain=gain)
        steps += int(out["steps"])
        cost = float(out["cost"])
        if last is None and not np.isfinite(cost):
            raise FitDivergedError(
                f"{', '.join(names)}: the {model.name} filter-error fit diverged (the filter's "
                "innovations are not finite from the start values); give start values closer "
                "to the answer or a smaller process_noise")
        if last is not None and not cost <= float(last["cost"]) + rise_max:
            # Local divergence after the F compensation (the gain grew too much for the new
            # R): halve the compensation twice, then go back and stop (the book's rule).
            # (The relaxation need not lower the cost at every pass: the R of the gain
            # changes what is minimised; a rise of the log-likelihood beyond `rise_max`,
            # the R elements 2 % larger on average, is divergence.)
            halvings += 1
            if halvings > 2 or alt is None:
                out = last
                break
            theta = theta.at[p:].set(0.5 * (theta[p:] + alt[0][p:]))
            continue
        last, halvings = out, 0
        moved += int(out["accepted"])
        theta = out["theta"]
        R_new = out["R"]
        change = float(jnp.max(jnp.abs(jnp.diag(R_new) / jnp.diag(Rk) - 1)))
        if _DEBUG:
            print(f"  outer {outer}: {int(out['steps'])} steps, cost {cost:.8g}, "
                  f"R change {change:.3g}, F {np.asarray(theta[p:])}")
        if not np.isfinite(change) or change <= outer_rtol:
            break
        alt = (theta, Rk)
        # A damped update: each diagonal element of R moves by a factor of 10 at most per
        # pass (from the output-error R of a poor start it can fall a thousandfold, and the
        # gain would outgrow the compensation of F)
        ratio = jnp.clip(jnp.diag(R_new) / jnp.diag(Rk), 0.1, 10.0)
        R_new = jnp.diag(jnp.diag(Rk) * ratio) if diagonal else R_new
        f = compensate_f(theta[p:], out["C"], Rk, R_new)
        theta = theta.at[p:].set(jnp.asarray(f))
        Rk = R_new
    theta = last["theta"]
    # the relaxation settled, and the Gauss-Newton passes moved the estimates at all (a fit
    # whose every step failed from the start leaves R as it was: a stall, not convergence)
    converged = (np.isfinite(change) and change <= outer_rtol
                 and (moved > 0 or bool(last["converged"])))
    # entries the innovations no longer depend on (F grown without bound: the gain is one
    # and the filter trusts the measurements) are held, the others' uncertainty given them
    d = np.asarray(jnp.diag(out["M"]))
    held = ~np.isfinite(d) | (d <= 1e-12 * np.nanmax(np.where(np.isfinite(d), d, 0.0)))
    cov = covariance_held(out["M"], None, jnp.asarray(held.astype(int)) if held.any() else None)
    std = jnp.sqrt(jnp.abs(jnp.diag(cov)))
    v = out["v"]
    f_names = tuple(f"F_{s}" for s in model.states)
    free_names = free_layout(model, n_local)[2]
    all_names = (*free_names, *f_names)
    first = flight_params(merge_batch(model, theta[:p], n_local), 0)  # flight 0's locals
    fitted = start_model.with_params({k: first[k] for k in model.free})
    res = FilterErrorResult(
        model=fitted, names=all_names, theta=theta, std=std, std_cr=std, cov=cov,
        corr=correlation(cov), R=out["R"], cost=out["cost"], cost_history=out["hist"],
        passes=out["accepted"], steps=jnp.asarray(steps), converged=jnp.asarray(converged),
        start=start,
        noise="diagonal" if diagonal else "full",
        lag1=jnp.max(jax.vmap(lag1_autocorrelation)(v, batch.mask), axis=0),
        residual_corr=correlation(jnp.einsum("bki,bkj->ij", v, v)),
        F=jnp.abs(theta[p:]), K=out["K"], P=out["P"], innovations=v,
        whiteness=whiteness(v, batch.mask, model.outputs), outer=outer, gain=gain)
    # (the held entries have no std by design: the checks read the others, as at bounds)
    found = fit_warnings(dataclasses.replace(res, active=jnp.asarray(held.astype(int))), names,
                         max_steps, information=out["M"], method="filter-error")
    found = [w for w in found if "strongly coloured" not in w]  # the filter handles colour
    unbounded = [s for s, h in zip(model.states, held[p:]) if h]
    if unbounded:
        found.append(f"{', '.join(names)}: the {model.name} filter-error process noise on "
                     f"{', '.join(unbounded)} grew without bound (the values are in "
                     "report.json): the filter trusts those measurements fully, so the "
                     "estimates are those of one-sample-ahead prediction and the measurement "
                     "noise is below what these flights resolve; their F have no standard "
                     "deviation")
    if not res.white:
        bad = [k for k, w in res.whiteness.items() if not w["white"]]
        found.append(f"{', '.join(names)}: the {model.name} filter-error innovations are not "
                     f"white ({', '.join(bad)}): a missing effect rather than process noise; "
                     f"next: {advise('model-error', 'filter-error')}")
    return dataclasses.replace(res, warnings=tuple(found))

