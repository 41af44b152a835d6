"""How the maximum-likelihood estimates (Eqs. 10-11) move with the 5 Hz split between the
cycle-averaged and the flapping part (Sec. III.B), by the implicit function theorem."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..data._flight import Flight
from ..estimate._gauss_newton import NoiseModel, ml_cost
from ..estimate._output_error import raw_residuals
from ..estimate._problem import FitResult, free_layout, merge_batch
from ..models._greybox import GreyBoxModel
from ..simulation._averaged import averaged
from ..simulation._experiment import Experiment


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
    layout = tuple(free_layout(model, n_local)[2])
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
    """The output-error cost as a pure function `L(theta, cutoff)`, for its derivatives.

    `theta` are the free parameters and `cutoff` the split cut-off: inside `L` the flights
    are cycle-averaged at `cutoff` ([`fwid.cycle_averaged`][]) and cut to
    [`fwid.Experiment`][]s as [`fwid.identify`][] does.

    - `noise="relaxed"`: Eq. (10) with R from Eq. (11) at `theta` (plus [`fwid.fit`][]'s tiny
      floor), i.e. `N/2 ln det R(theta, cutoff) + const`, whose stationary point is what
      [`fwid.fit`][]'s relaxation converges to;
    - `noise="fixed"`: the data term of Eq. (10) with R held at `fit_result.R`,
      `1/2 sum_k v_k^T R^-1 v_k`.

    `theta` is laid out as `fit_result.theta` (`fit_result.names`); the parameters that were
    not estimated keep `fit_result.model`'s values. Jit-able, and differentiable in both
    arguments in forward mode (`jax.jacfwd`; reverse mode does not go through the diffrax
    simulation).

    **Arguments:** as [`fwid.estimate_sensitivity_to_cutoff`][]: `model`, `flight` (one or
    several), `fit_result` (the fit at the nominal cut-off), `noise` (`"relaxed"` or
    `"fixed"`), `noise_cutoff` [Hz] and `edge` (the seconds dropped at each end).

    **Returns:** the function `L(theta, cutoff)` -> scalar.
    """
    flights, _, n_local, base = _cutoff_setup(model, flight, fit_result, noise)
    R = np.asarray(fit_result.R)
    diagonal = bool(np.all(R[~np.eye(R.shape[0], dtype=bool)] == 0))
    Rinv = jnp.asarray(np.linalg.inv(R)) if noise == "fixed" else None

    def L(theta, cutoff):
        batch = _stack_traced([averaged(f, base, cutoff, noise_cutoff, edge) for f in flights])
        v = raw_residuals(base, merge_batch(base, theta, n_local), batch)
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
    """How the output-error estimates move with the split cut-off (5 Hz, Sec. III.B).

    `d theta_hat / d cutoff`, by the implicit function theorem.

    The estimate is a stationary point of the cost, `g(theta, c) = dL/dtheta = 0`, where the
    data (the cycle-averaged outputs `z`, inputs `u` and initial state `x0`) depend on the
    cut-off `c` through the zero-phase split ([`fwid.cycle_averaged`][], differentiable in
    `c`), exactly as [`fwid.identify`][] builds them (0.2 s dropped at each end). Then

    $$\\frac{d\\hat\\theta}{dc} = -\\Big(\\frac{\\partial g}{\\partial\\theta}\\Big)^{-1}
    \\frac{\\partial g}{\\partial c},$$

    with the full Hessian `dg/dtheta` (second derivatives of the simulation included, not the
    Gauss-Newton approximation) and `dg/dc`, both by forward-over-forward autodiff through the
    filter and the diffrax simulation of [`fwid.cutoff_cost`][]'s `L`:

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
