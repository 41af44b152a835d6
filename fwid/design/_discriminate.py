"""`design_discriminating`: the input that best tells two models apart.

When two effects explain a gap about equally well, the two augmented models fitted to the same
flights agree on those flights. The next flight should make them disagree: the input
maximises the expected difference between their predicted outputs, normalised by the noise,
`D = sum_k (y_a,k - y_b,k)^T R^-1 (y_a,k - y_b,k)` (the log-likelihood ratio one flight would
give in favour of the true model, twice over: its expected value under either model is
`D / 2`), under the same limits as [`fwid.design_input`][].

With `loads_a`, `loads_b` the difference is that of the two models' predicted loads along one
trajectory, what an equation-error comparison (the diagnosis's) sees on the flown flight:
`D = 1/2 sum_j sum_k |S^-1 (L_a(x_j,k) - L_b(x_j,k) - mean)|^2`, the trajectory `x_j`
simulated by either model in turn (the flight is flown by one of them), the mean over the
flight removed (a flight's trim load is its own), `S` the loads' scale.

A model fitted on small manoeuvres may diverge for a large one (the quadratic terms of
`nonlinear-aero` in the simulated states, extrapolated). The reference 3211 (the attitude
bound, and with steps one restart, so that a gradient exists) is the first whose predictions
by both models stay finite: filling the window, else faster (units of T/14, T/28), else at
half the amplitude, and so on (`limits["amplitude_used_rad"]`,
`limits["reference_3211_unit_s"]`). The comparison is the window-filling 3211 of the
amplitude used; its `distance_3211` is `nan` when a model's prediction of it diverges.

The free optimisation is one candidate among the classic inputs that tell amplitude from
rate (`alternatives`): a state nonlinearity grows with the size of the manoeuvre, a servo's
lag or rate limit with the speed of the control. The window-filling 3211 at the amplitude
used and at half of it, a fast 3211 (unit T/28) and a fast doublet (unit T/14), each under
the same attitude bound, are scored by the same `D`; the input returned is the one of them
or the optimised one with the largest (`settings["chosen"]`, every one's `D` in
`criterion["alternatives"]`).
"""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._errors import InputError
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate
from ._design import check_limits
from ._optimise import _say, minimise
from ._criterion import parametrisation as _parametrisation
from ._signals import Grid, doublet, input_3211, step_index


class Discrimination(eqx.Module):
    """A discriminating input: `t`, `u` (the control), the two models' predicted outputs
    `response_a`, `response_b` `(n, outputs)`, the expected difference `distance` (`D`) and
    that of a 3211 of the same amplitude and length (`distance_3211`, `u_3211`; the amplitude
    used, `limits["amplitude_used_rad"]`, is below the one asked for where a model's
    prediction diverged), `limits`, `settings`."""

    t: np.ndarray
    u: np.ndarray
    outputs: tuple
    response_a: np.ndarray
    response_b: np.ndarray
    distance: float
    distance_3211: float
    u_3211: np.ndarray
    limits: dict
    settings: dict
    criterion: str = "outputs"
    alternatives: dict = eqx.field(default_factory=dict)

    def to_json(self) -> dict:
        name = ("expected difference of the two models' predicted outputs, sum_k d_k^T R^-1 "
                "d_k" if self.criterion == "outputs" else
                "expected difference of the two models' predicted loads along either "
                "model's trajectory, the flight's mean removed, sum_k d_k^T S^-2 d_k")
        return {"criterion": {"name": name,
                              "designed": self.distance, "3211": self.distance_3211,
                              "ratio": self.distance / max(self.distance_3211, 1e-300)
                              if np.isfinite(self.distance_3211) else None,
                              "alternatives": self.alternatives},
                "limits": self.limits, "settings": self.settings}


#: How often the amplitude is halved while a model's prediction of a 3211 diverges.
HALVINGS = 6


def _finite(ys, att: int | None) -> bool:
    """Whether predictions stay finite (and the attitude, when given, within a half turn:
    beyond it a model has left every region it was fitted in)."""
    for y in ys:
        y = np.asarray(y)
        if not np.all(np.isfinite(y)) or (att is not None and np.max(np.abs(y[:, att])) > np.pi):
            return False
    return True


def _steps_start(grid: Grid, pattern: np.ndarray, switch_rate: float) -> jnp.ndarray:
    """The step coefficients `x` (`A tanh(x)`) nearest the signal `pattern` (in units of
    the amplitude): its mean over each step, kept inside `tanh`'s range."""
    idx, k = step_index(grid, switch_rate)
    mean = np.array([np.mean(pattern[idx == j]) if np.any(idx == j) else 0.0
                     for j in range(k)])
    return jnp.asarray(np.arctanh(np.clip(mean, -0.95, 0.95)))


def _default_inputs(model: GreyBoxModel) -> Callable:
    nu = len(model.inputs)

    def inputs(t, u):
        return jnp.zeros((u.shape[0], nu)).at[:, 0].set(u)
    return inputs


def design_discriminating(
    model_a: GreyBoxModel,
    model_b: GreyBoxModel,
    *,
    consts,
    R,
    amplitude: float,
    duration: float = 5.0,
    quiet: float = 1.0,
    inputs_a: Callable | None = None,
    inputs_b: Callable | None = None,
    parametrisation: str = "steps",
    switch_rate: float = 10.0,
    band: tuple[float, float] = (0.0, 3.0),
    rate: float = 100.0,
    attitude: str | None = None,
    attitude_bound: float | str | None = "3211",
    restarts: int = 4,
    iterations: int = 300,
    seed: int = 0,
    progress=False,
    loads_a: Callable | None = None,
    loads_b: Callable | None = None,
    load_scale=None,
) -> Discrimination:
    """Design the input that maximises the noise-normalised difference of two models'
    predicted outputs.

    **Arguments:**
    - `model_a`, `model_b`: the two models (the same outputs; each at its estimate, at trim).
    - `consts`, `R`: the constants and the noise covariance of the outputs.
    - `inputs_a`, `inputs_b`: `(t, u) -> (n, model inputs)`, the model's inputs for the
      control `u` (e.g. the control through a diagnosed lag); default: `u` as the first input,
      the others zero.
    - `attitude`, `attitude_bound`: the output whose predicted excursion (by either model) is
      bounded, and the bound (rad; `"3211"`: that of a 3211 of the same amplitude).
    - `loads_a`, `loads_b`: `(t, u, y) -> (n, loads)`, a model's predicted loads along the
      trajectory `y` (its outputs) for the control `u`; given both, `D` compares the loads
      (the module's docstring), `load_scale` (per load; default: the standard deviation of
      model a's loads along its own prediction of the reference 3211) their scale.
    - the rest as in [`fwid.design_input`][].

    **Returns:** a [`fwid.design.Discrimination`][].
    """
    check_limits(duration, amplitude, quiet, rate, switch_rate)
    if model_a.outputs != model_b.outputs:
        raise InputError(f"design: the two models have different outputs "
                         f"({model_a.outputs} vs {model_b.outputs})")
    inputs_a = inputs_a or _default_inputs(model_a)
    inputs_b = inputs_b or _default_inputs(model_b)
    grid = Grid(duration, quiet, rate)
    consts = {k: jnp.asarray(v, dtype=float) for k, v in dict(consts).items()}
    W = jnp.asarray(np.linalg.cholesky(np.linalg.inv(np.atleast_2d(R))).T)
    att = model_a.outputs.index(attitude) if attitude in model_a.outputs else None

    def responses(u):
        out = []
        for m, inp in ((model_a, inputs_a), (model_b, inputs_b)):
            uu = inp(grid.t, u)
            exp = Experiment(grid.t, uu, jnp.zeros((grid.t.size, len(m.outputs))),
                             x0=jnp.zeros(len(m.states)), consts=consts,
                             mask=np.ones(grid.t.size))
            out.append(simulate(m, exp)[1])
        return out

    # the reference 3211 (the attitude bound, a restart): at the full amplitude, filling the
    # window or faster (units of T/7, T/14, T/28, no shorter than a step), else halved
    units = [grid.length / k for k in (7, 14, 28) if grid.length / k >= 1.0 / switch_rate
             or k == 7]

    def reference():
        for h in range(HALVINGS + 1):
            for unit in units:
                ref = input_3211(grid, amplitude / 2**h, unit)
                ys = responses(jnp.asarray(ref))
                if _finite(ys, att):
                    return amplitude / 2**h, ref, unit, ys
        raise InputError(f"design: a model's prediction diverges even for a 3211 of "
                         f"{amplitude / 2**HALVINGS:.3g} rad ({amplitude:g} rad / "
                         f"2^{HALVINGS}): that model is unstable at trim; check its fit "
                         "(re-fit it on more flights) before designing with it")

    used, ref, unit, ys_ref = reference()
    by_loads = loads_a is not None and loads_b is not None
    if not by_loads:
        scale = None
    elif load_scale is not None:
        scale = jnp.asarray(load_scale, dtype=float)
    else:  # model a's loads along its own prediction of the reference 3211
        la = np.asarray(loads_a(grid.t, jnp.asarray(ref), ys_ref[0]))
        scale = jnp.asarray(np.std(la, axis=0) + 1e-12 * np.max(np.abs(la)) + 1e-300)

    def load_difference(u, ys):
        out = 0.0
        for y in ys:
            d = loads_a(grid.t, u, y) - loads_b(grid.t, u, y)
            out = out + 0.5 * jnp.sum(((d - jnp.mean(d, axis=0)) / scale) ** 2)
        return out

    def distance(u):
        ya, yb = responses(u)
        if by_loads:
            return load_difference(u, (ya, yb)), ya, yb
        d = (ya - yb) @ W.T
        return jnp.sum(d**2), ya, yb

    u3211 = input_3211(grid, used)  # the comparison: filling the window
    if att is None or attitude_bound is None:
        bound = None
    elif attitude_bound == "3211":
        bound = float(max(np.max(np.abs(np.asarray(y)[:, att])) for y in ys_ref))
    else:
        bound = float(attitude_bound)

    def bounded(u):
        if bound is None:
            return u
        ya, yb = responses(u)
        peak = jnp.maximum(jnp.max(jnp.abs(ya[:, att])), jnp.max(jnp.abs(yb[:, att])))
        # a prediction that diverges (a nonlinear model) counts as over the bound
        return u * jnp.where(jnp.isfinite(peak), jnp.minimum(1.0, bound / peak), 0.0)

    basis, coef, start = _parametrisation(parametrisation, grid, used, switch_rate, band)
    E = jnp.asarray(basis)

    def signal(x):
        return coef(x) @ E

    def loss(x):  # the log: the distance spans decades between starts
        return -jnp.log(distance(bounded(signal(x)))[0] + 1e-300)

    starts = jax.vmap(start)(jax.random.split(jax.random.PRNGKey(seed), restarts))
    if parametrisation == "steps":
        # one restart from the 3211 (finite there): the design starts from the input it is
        # compared with, and random full-amplitude steps may all diverge, where the bounded
        # signal is zero and has no gradient
        starts = starts.at[0].set(_steps_start(grid, ref / used, switch_rate))
    _say(progress, f"discriminating design: {parametrisation}, {restarts} restarts")
    xs, fs, _ = minimise(loss, starts, iterations=iterations,
                         learning_rate=0.05 if parametrisation == "multisine" else 0.1,
                         progress=progress, label="discriminating design")
    u = np.asarray(bounded(signal(jnp.asarray(xs[int(np.argmin(fs))]))))
    D, ya, yb = distance(jnp.asarray(u))
    chosen, scored = "optimised", {"optimised": float(D)}
    for name, alt in alternatives(grid, used).items():
        ua = np.asarray(bounded(jnp.asarray(alt)))
        Da, yaa, yba = distance(jnp.asarray(ua))
        scored[name] = float(Da) if np.isfinite(float(Da)) else None
        if np.isfinite(float(Da)) and (not np.isfinite(float(D)) or float(Da) > float(D)):
            chosen, u, D, ya, yb = name, ua, Da, yaa, yba
    if not np.isfinite(float(D)):
        raise InputError(f"design: the two models' predictions diverge for every input "
                         f"tried (peak {used:.3g} rad); lower the amplitude or give a smaller "
                         "attitude bound")
    if float(D) <= 0:
        raise InputError("design: the two models predict the same outputs for every input "
                         "tried: the effects differ only through inputs the control does not "
                         "drive (held at zero); fly a manoeuvre that excites those instead")
    D3, ya3, yb3 = distance(jnp.asarray(u3211))

    def peak(*ys):
        return None if att is None else float(max(np.max(np.abs(np.asarray(y)[:, att]))
                                                  for y in ys))

    limits = {"amplitude_rad": amplitude, "amplitude_used_rad": used,
              "reference_3211_unit_s": float(unit),
              "peak_rad": float(np.max(np.abs(u))),
              "duration_s": grid.duration, "quiet_s": grid.quiet,
              "attitude": attitude if att is not None else None,
              "attitude_bound_rad": bound, "attitude_peak_rad": peak(ya, yb),
              "attitude_peak_3211_rad": peak(ya3, yb3)}
    return Discrimination(t=grid.t, u=u, outputs=model_a.outputs, response_a=np.asarray(ya),
                          response_b=np.asarray(yb), distance=float(D),
                          distance_3211=float(D3), u_3211=u3211, limits=limits,
                          settings={"parametrisation": parametrisation, "rate_hz": rate,
                                    "restarts": restarts, "iterations": iterations,
                                    "seed": seed, "chosen": chosen},
                          criterion="loads" if by_loads else "outputs", alternatives=scored)


def alternatives(grid: Grid, amplitude: float) -> dict[str, np.ndarray]:
    """The classic inputs scored beside the optimised one (module docstring): amplitude
    against rate."""
    return {"3211": input_3211(grid, amplitude),
            "3211 half amplitude": input_3211(grid, amplitude / 2),
            "fast 3211": input_3211(grid, amplitude, grid.length / 28),
            "fast doublet": doublet(grid, amplitude, grid.length / 14)}
