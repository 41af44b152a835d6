"""The equation-error method: least squares on the reconstructed loads (the paper's Eqs. 1-6).

Where the paper starts its output-error fits (Sec. IV.B), and where a flight-test engineer
starts on an unstable vehicle flown in closed loop (Klein and Morelli, *Aircraft System
Identification*, Ch. 5; SIDPAC's `lesq`): no simulation, so neither instability nor feedback
can make it diverge.

Two linear regressions at the measured states and inputs, in turn:

1. **the loads**: each reconstructed cycle-averaged force and moment (`model.forces`, Eqs.
   1-6) on the states and inputs, with an intercept of its own per load and per flight (the
   flight's trim error, which the perturbation loads carry: a nuisance, not reported); the
   parameters the force model depends on come from here;
2. **the state equations**: the numerically differentiated measured states on `f(x, u, p,
   c)` (Eq. 7), the parameters of step 1 held, for the rest: the bias terms (`model.local`,
   one set per flight) and, for a model without a force model or without reconstructed
   loads (the textbook aircraft models), every free parameter.

Each regression is weighted by its residual variance (per equation) and solved exactly
(the model is linear in the parameters; a few Gauss-Newton steps where it is not). The
standard errors are corrected for coloured residuals as SIDPAC's `r_colores` (Morelli and
Klein): `M^-1 (sum_i sum_j S_i^T R_vv(i - j) S_j) M^-1`, here with the Bartlett lag window
of the other methods (`fwid.estimate._uncertainty.coloured_residual_middle`); the two
regressions' covariances are kept apart (block diagonal: step 2's uncertainty is conditional
on step 1's estimates).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._errors import InputError
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ._colour import colour_at_bandwidth
from ._problem import FitResult, free_layout, prepare
from ._regression import derivative, stacked
from ._uncertainty import (coloured_residual_middle, correlation, correlation_length,
                           covariance, lag1_autocorrelation)
from ._warnings import fit_warnings, issue, quiet_fits


def _design(fn, params, names, exps, targets):
    """Per experiment, the residual `target - fn(x, u, p, c)` at `params` `(n, k)` and its
    sensitivity to `names` `(n, k, p)`: the regression's target and regressors."""
    if not names:
        return [(np.asarray(y) - np.asarray(jax.vmap(lambda x, u: fn(x, u, params, e.consts))(
            e.z, e.u)), np.zeros((*np.shape(y), 0))) for e, y in zip(exps, targets)]
    theta = jnp.stack([jnp.asarray(params[k], dtype=float) for k in names])
    out = []
    for e, y in zip(exps, targets):
        r, J = stacked(fn, params, names, [e], [y], 1.0)(theta)
        k = np.asarray(y).shape[1]
        out.append((r.reshape(-1, k), -J.reshape(-1, k, len(names))))
    return out


def _whitener(v: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """Per equation, one over the residuals' rms (a diagonal weighting), the rms floored at
    `1e-9` of the equation's own `scale` (a noise-free equation keeps a finite weight)."""
    s = np.sqrt(np.mean(v**2, axis=0))
    floor = 1e-9 * (np.ones_like(s) if scale is None else scale) + np.finfo(float).tiny
    return 1.0 / np.maximum(s, floor)


class _Regression:
    """One weighted linear regression over several experiments: `r_i = S_i dtheta + v_i`,
    with the regressors `S_i` `(n, k, p)` mapped onto the columns `cols_i` of the whole
    parameter vector (`p_all` entries)."""

    def __init__(self, blocks, cols, p_all):
        self.blocks, self.cols, self.p_all = blocks, cols, p_all

    def _full(self, S, cols):
        out = np.zeros((*S.shape[:2], self.p_all))
        out[:, :, cols] = S
        return out

    def solve(self, passes: int = 3):
        """The weighted least-squares step, the weights relaxed to the residual variance of
        each equation (`passes` times); returns `(dtheta, v_i, S_i whitened, weights)`."""
        scale = np.sqrt(np.mean(np.concatenate([r for r, _ in self.blocks]) ** 2, axis=0))
        W = _whitener(np.concatenate([r for r, _ in self.blocks]))
        if self.p_all == 0:  # nothing to estimate: the residuals are the targets'
            return (np.zeros(0), [r for r, _ in self.blocks],
                    [np.zeros((*r.shape, 0)) for r, _ in self.blocks], W)
        for _ in range(passes):
            A = np.concatenate([(self._full(S, c) * W[None, :, None]).reshape(-1, self.p_all)
                                for (r, S), c in zip(self.blocks, self.cols)])
            b = np.concatenate([(r * W).ravel() for r, _ in self.blocks])
            ok = np.isfinite(b) & np.all(np.isfinite(A), axis=1)
            step, *_ = np.linalg.lstsq(A[ok], b[ok], rcond=None)
            vs = [r - self._full(S, c) @ step for (r, S), c in zip(self.blocks, self.cols)]
            W = _whitener(np.concatenate(vs), scale)
        Sw = [self._full(S, c) * W[None, :, None] for (_, S), c in zip(self.blocks, self.cols)]
        return step, vs, Sw, W


def _uncertainty(Sw, vws):
    """`(M, middle)`: the information of the whitened regressors and the middle term of the
    covariance corrected for the residuals' colour (each experiment's own lags)."""
    M = sum(S.reshape(-1, S.shape[-1]).T @ S.reshape(-1, S.shape[-1]) for S in Sw)
    mid = 0.0
    for S, v in zip(Sw, vws):
        mask = jnp.ones(v.shape[0])
        lag = 2 * int(correlation_length(jnp.asarray(v), mask))
        mid = mid + np.asarray(coloured_residual_middle(jnp.asarray(S), jnp.asarray(v), mask,
                                                        max_lag=lag))
    return M, mid


def measured_state_index(model: GreyBoxModel) -> np.ndarray | None:
    """The indices of the states among the outputs (`None` when some state is not
    measured)."""
    if model.outputs_are_states:
        return np.arange(len(model.states))
    if model.measured_states is not None:
        return np.asarray(model.measured_states)
    return None


def _state_equations(model: GreyBoxModel) -> np.ndarray:
    """The indices of the measured states among the outputs (equation error needs them)."""
    idx = measured_state_index(model)
    if idx is not None:
        return idx
    raise InputError(f"the {model.name} model's states are not all measured (outputs "
                     f"{', '.join(model.outputs)}): equation error regresses the measured "
                     "state derivatives; fit it by output error")


def _regress(fn, params, layout, exps, targets, extra: int = 0, iters: int = 5):
    """Regress `targets` on `fn` at the measured states over all `exps`: the parameters
    `layout[i]` (names of the whole vector, `name@i` for flight `i`'s own copy of a local
    one) of each flight, plus `extra` intercepts per equation and flight when `extra`.
    Gauss-Newton from `params` (one step when `fn` is linear in them).

    **Returns:** `(values, (v, Sw, W, names))`: the estimates by name of the whole vector;
    per flight the residuals and the whitened regressors (the intercepts' columns last), the
    equation weights, and the names of the regressors' first columns."""
    names = list(dict.fromkeys(n for lay in layout for n in lay))
    col = {n: i for i, n in enumerate(names)}
    values = {n: float(np.asarray(params[n.split("@")[0]])) for n in names}
    p = len(names)
    k = np.asarray(targets[0]).shape[1]
    p_all = p + extra * k * len(exps)
    for _ in range(iters):
        blocks, cols = [], []
        for i, (e, y, lay) in enumerate(zip(exps, targets, layout)):
            pi = {**params, **{n.split("@")[0]: values[n] for n in lay}}
            base = [n.split("@")[0] for n in lay]
            (r, S), = _design(fn, pi, base, [e], [y])
            c = [col[n] for n in lay]
            if extra:
                S = np.concatenate([S, np.broadcast_to(np.eye(k)[None], (r.shape[0], k, k))],
                                   axis=2)
                c += [p + i * k + j for j in range(k)]
            blocks.append((r, S))
            cols.append(c)
        step, vs, Sw, W = _Regression(blocks, cols, p_all).solve()
        for n in names:
            values[n] += float(step[col[n]])
        if np.all(np.abs(step[:p]) <= 1e-12 * (1.0 + np.abs([values[n] for n in names]))):
            break
    return values, (vs, Sw, W, names)


def _residual_statistics(vs, xs) -> dict:
    """`lag1`, `colour`, `residual_corr` of the state equations' residuals (per output where
    the outputs are the states; the largest over the flights)."""
    ones = [jnp.ones(v.shape[0]) for v in vs]
    v = np.concatenate(vs)
    return dict(
        lag1=jnp.max(jnp.stack([lag1_autocorrelation(jnp.asarray(a), m)
                                for a, m in zip(vs, ones)]), axis=0),
        colour=jnp.max(jnp.stack([colour_at_bandwidth(jnp.asarray(a), x, m)
                                  for a, x, m in zip(vs, xs, ones)]), axis=0),
        residual_corr=correlation(jnp.asarray(v.T @ v)))


def fit_equation_error(
    model: GreyBoxModel,
    exps: Sequence[Experiment],
    *,
    names: Sequence[str],
    start=None,
    noise: str = "auto",
    max_steps: int = 60,
    rtol: float = 1e-10,
    cost_rtol: float = 1e-10,
    progress: bool = False,
    local_per_flight: bool | None = None,
) -> FitResult:
    """[`fwid.fit`][] with `method="equation-error"` (see the module docstring).

    The bias terms (`model.local`) are estimated per flight when there are several (named
    `bq@0`, `bq@1`, ... as in a joint output-error fit; `local_per_flight=False` shares
    them). `start`, `noise`, `max_steps`, `rtol`, `cost_rtol` are accepted for a common
    signature and not used: the regressions are solved exactly.

    **Returns:** a [`fwid.FitResult`][] whose `R` is the covariance of the state equations'
    residuals (their units per second), `cost` half the weighted sum of squares of both
    regressions, `converged` true when both solves are finite and of full rank, `std`
    corrected for coloured residuals and `std_cr` the plain least-squares ones.
    """
    t0 = time.perf_counter()
    exps, names = list(exps), list(names)
    prepare(model, exps, names, "model", 0)  # the checks every method makes (no start here)
    idx = _state_equations(model)
    many = len(exps) > 1 and bool(model.local) and local_per_flight is not False
    n_local = len(exps) if many else 0
    all_names = free_layout(model, n_local)[2]
    params = {k: jnp.asarray(v, dtype=float) for k, v in model.params.items()}
    if progress:
        print(f"fwid: fitting {model.name} by equation error to {', '.join(names)} ...",
              flush=True)

    def own(subset, i):  # flight i's entries of the whole vector among `subset`
        return [n for n in all_names if n.split("@")[0] in subset
                and ("@" not in n or n == f"{n.split('@')[0]}@{i}")]

    # 1. the loads, with an intercept per load and flight
    load_free: list[str] = []
    if model.forces is not None and all(e.forces is not None for e in exps):
        probe = _design(model.forces, params, list(model.free), exps[:1], [exps[0].forces])
        reach = np.any(np.asarray(probe[0][1]) != 0, axis=(0, 1))
        load_free = [k for k, hit in zip(model.free, reach) if hit]
    regressions, values = [], {}
    if load_free:
        got, reg = _regress(model.forces, params, [own(load_free, i) for i in range(len(exps))],
                            exps, [e.forces for e in exps], extra=1)
        values.update(got)
        params.update({n: jnp.asarray(v) for n, v in got.items() if "@" not in n})
        regressions.append(reg)

    # 2. the state equations for the rest, the loads' parameters held
    rest = [k for k in model.free if k not in load_free]
    xs = [jnp.asarray(np.asarray(e.z)[:, idx]) for e in exps]
    xexps = [e if model.outputs_are_states else eqx.tree_at(lambda a: a.z, e, x)
             for e, x in zip(exps, xs)]
    xdots = [jnp.asarray(derivative(e.t, x)) for e, x in zip(exps, xs)]
    got, reg = _regress(model.f, params, [own(rest, i) for i in range(len(exps))], xexps,
                        xdots)
    values.update(got)
    regressions.append(reg)
    theta = np.array([values[n] for n in all_names])

    # uncertainty: each regression's block, coloured-residual corrected
    p = len(all_names)
    cov, cov_cr, M_all = np.zeros((p, p)), np.zeros((p, p)), np.zeros((p, p))
    cost = 0.0
    full_rank = True
    for vs, Sw, W, regressors in regressions:
        vws = [v * W for v in vs]
        cost += 0.5 * sum(float(np.sum(v**2)) for v in vws)
        if not regressors:
            continue
        M, mid = _uncertainty(Sw, vws)  # the intercepts' columns included ...
        d = np.sqrt(np.clip(np.diag(M), 0, None))
        with np.errstate(all="ignore"):  # rank of the information scaled to a unit diagonal
            full_rank &= bool(np.all(d > 0)
                              and np.linalg.matrix_rank(M / np.outer(d, d)) == len(M))
            C = np.asarray(covariance(jnp.asarray(M), jnp.asarray(mid)))
            C_cr = np.asarray(covariance(jnp.asarray(M)))
        k = len(regressors)  # ... and the parameters' block kept: intercepts marginalised
        where = [all_names.index(n) for n in regressors]
        sub = np.ix_(where, where)
        cov[sub], cov_cr[sub] = C[:k, :k], C_cr[:k, :k]
        with np.errstate(all="ignore"):  # their information, the intercepts marginalised
            M_all[sub] = np.linalg.pinv(C_cr[:k, :k]) if np.all(np.isfinite(C_cr)) \
                else M[:k, :k]
    finite = bool(np.all(np.isfinite(theta)) and np.all(np.isfinite(cov)))
    vs2 = regressions[-1][0]
    v2 = np.concatenate(vs2)
    first = {n.split("@")[0]: theta[i] for i, n in enumerate(all_names)
             if "@" not in n or n.endswith("@0")}
    res = FitResult(
        model=model.with_params(first), names=tuple(all_names), theta=jnp.asarray(theta),
        std=jnp.sqrt(jnp.abs(jnp.diag(jnp.asarray(cov)))),
        std_cr=jnp.sqrt(jnp.abs(jnp.diag(jnp.asarray(cov_cr)))), cov=jnp.asarray(cov),
        corr=correlation(jnp.asarray(cov)), R=jnp.asarray(v2.T @ v2 / v2.shape[0]),
        cost=jnp.asarray(cost), cost_history=jnp.asarray([cost]), passes=jnp.asarray(1),
        steps=jnp.asarray(1), converged=jnp.asarray(full_rank and finite),
        start=jnp.asarray(theta), noise="diagonal",
        **(_residual_statistics(vs2, xs) if model.outputs_are_states else {}))
    found = [w for w in fit_warnings(res, names, None, information=M_all)
             if "strongly coloured" not in w]  # the std allow for it; no simulation to blame
    if not full_rank:
        found.insert(0, f"{', '.join(names)}: the {model.name} equation-error regressors are "
                        "linearly dependent: the flights do not excite every term")
    res = dataclasses.replace(res, warnings=tuple(found))
    issue(res.warnings, stacklevel=4)
    if progress:
        print(f"fwid: equation error {'solved' if bool(res.converged) else 'NOT solved'}, "
              f"{time.perf_counter() - t0:.1f} s", flush=True)
    return res


def equation_error_locals(model: GreyBoxModel, exp: Experiment, name: str) -> dict[str, float]:
    """A flight's own bias terms (`model.local`) by equation error, every other parameter
    held: the mean of the state equations' residuals at the measured states, which needs no
    simulation (an unstable model's diverges). How a held-out flight's biases are
    re-estimated where its simulation cannot be trusted."""
    with quiet_fits():
        r = fit_equation_error(model.with_free(model.local), [exp], names=[name])
    return {k: float(v) for k, v in zip(r.names, np.asarray(r.theta))}


def loads_at_measured_states(model: GreyBoxModel, exp: Experiment) -> np.ndarray:
    """The model's loads (`model.forces`, Eqs. 1-6) at the flight's measured states and
    inputs, each offset by the flight's mean load residual (its trim error, the intercept of
    the loads' regression): what equation error predicts for a flight `(n, loads)`."""
    idx = _state_equations(model)
    x = jnp.asarray(np.asarray(exp.z)[:, idx])
    F = np.asarray(jax.vmap(lambda xk, uk: model.forces(xk, uk, model.params, exp.consts))(
        x, exp.u))
    return F + np.mean(np.asarray(exp.forces) - F, axis=0)


def equation_error_start(model: GreyBoxModel, exps: Sequence[Experiment], names: Sequence[str],
                         start):
    """`(start, result)`: with `start="least-squares"` and the model's states measured, the
    equation-error estimate (biases shared by the flights) and its [`fwid.FitResult`][],
    where the methods that filter or restart from the measured states (filter error,
    multiple shooting) begin; otherwise `start` as given and `None`."""
    if not (isinstance(start, str) and start == "least-squares") \
            or measured_state_index(model) is None:
        return start, None
    with quiet_fits():
        ee = fit_equation_error(model, list(exps), names=list(names), local_per_flight=False)
    return (ee.model, ee) if bool(ee.converged) else (start, None)
