"""`design_input`: the test input for the next flight that minimises the predicted standard
deviations of the parameters, by gradients through the model (the test-input format)."""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._errors import InputError
from ..data._flight import Flight
from ..models._greybox import GreyBoxModel
from ..simulation._averaged import averaged
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate
from ._affine import affine_responses
from ._criterion import AffineLoss, objective, parametrisation as _parametrisation
from ._information import (Setting, absolute, information, prior_matrix,
                           vehicle_information)
from ._optimise import _say, flip_search, minimise
from ._signals import Grid, input_3211
from ._source import ATTITUDE, CONTROL, from_identification, from_report, report_prior

#: The share of a given attitude limit the model's prediction may use (the rest is the
#: margin for its error).
MARGIN = 0.8
PENALTY = 100.0


CRITERION_NAMES = {
    "d-optimal": "D-optimal: log det of the Fisher information of the vehicle's parameters "
                 "(biases as per-flight nuisance parameters), relative units",
    "variances": "-sum log diag M^-1 of the Fisher information M of the vehicle's parameters "
                 "(biases as per-flight nuisance parameters): minus twice the parameter count "
                 "times the log of the geometric mean of their predicted standard deviations, "
                 "relative units"}


class Design(eqx.Module):
    """A designed input and what the model predicts of it.

    **Fields:**
    - `t`, `u`: the time (s, from 0) and the control (rad, perturbation from trim).
    - `control`: the control's name (`de`, `dr`, ...); `outputs`, `response`: the outputs'
      names and their predicted perturbations `(n, outputs)` for the input.
    - `names`: the free parameters; `std`, `std_3211`: their predicted standard deviations
      (Cramer-Rao) for the designed input and for a 3211 of the same amplitude and length
      (with the flights already flown and the prior); `ratio = std_3211 / std`.
    - `information`, `information_3211`: the vehicle's parameters' information matrices
      (own units; flown flights and prior included) and `vehicle_names` their order.
    - `criterion`, `criterion_3211`: the design criterion (`settings["criterion"]`) of the
      relative information, maximised.
    - `limits`: amplitude, duration, quiet, attitude limit and margin, the predicted peak
      attitude excursion of the design and of the 3211, whether the other control is held.
    - `settings`: parametrisation, restarts, iterations, noise source, rate.
    """

    t: np.ndarray
    u: np.ndarray
    control: str
    outputs: tuple
    response: np.ndarray
    names: tuple
    std: np.ndarray
    std_3211: np.ndarray
    ratio: np.ndarray
    vehicle_names: tuple
    information: np.ndarray
    information_3211: np.ndarray
    criterion: float
    criterion_3211: float
    u_3211: np.ndarray
    response_3211: np.ndarray
    limits: dict
    settings: dict

    def table(self) -> dict:
        """`{name: {"designed", "3211", "ratio"}}` of the predicted standard deviations."""
        return {k: {"designed": float(a), "3211": float(b), "ratio": float(r)}
                for k, a, b, r in zip(self.names, self.std, self.std_3211, self.ratio)}

    def to_json(self) -> dict:
        """The `design.json` of `fwid design` (the test-input format)."""
        return {
            "model": self.settings.get("model"),
            "control": self.control,
            "criterion": {"name": CRITERION_NAMES[self.settings.get("criterion",
                                                                    "d-optimal")],
                          "designed": self.criterion, "3211": self.criterion_3211},
            "parameters": self.table(),
            "geometric_mean_ratio": float(np.exp(np.mean(np.log(
                self.ratio[[self.names.index(k) for k in self.vehicle_names]])))),
            "limits": self.limits,
            "settings": self.settings,
            "std_kind": "Cramer-Rao (inverse Fisher information with the fit's R; white "
                        "noise assumed: fwid's reported std, corrected for coloured "
                        "residuals, is larger by the same factor for both inputs)",
        }


def _source(model_or_identification, model, consts, R):
    if isinstance(model_or_identification, GreyBoxModel):
        if consts is None or R is None:
            raise InputError("design_input: with a GreyBoxModel give consts= and R= too")
        return model_or_identification, dict(consts), np.asarray(R, float), "given R"
    if isinstance(model_or_identification, (str, dict)) or hasattr(model_or_identification,
                                                                   "is_file"):
        return from_report(model_or_identification, model)
    if hasattr(model_or_identification, "fits") and hasattr(model_or_identification, "model"):
        return from_identification(model_or_identification)
    raise InputError("design_input: give a report.json path, its dict, an Identification or "
                     "a GreyBoxModel")


def check_limits(duration, amplitude, quiet, rate, switch_rate=None) -> None:
    """One-line errors for limits that cannot hold."""
    if not np.isfinite(amplitude) or amplitude <= 0:
        raise InputError(f"design: amplitude must be > 0 rad, got {amplitude}")
    if not np.isfinite(duration) or duration <= 0:
        raise InputError(f"design: duration must be > 0 s, got {duration}")
    if not np.isfinite(quiet) or quiet < 0 or quiet >= duration:
        raise InputError(f"design: quiet start must be >= 0 s and shorter than the duration "
                         f"({duration} s), got {quiet}")
    if not np.isfinite(rate) or rate <= 0 or (duration - quiet) * rate < 4:
        raise InputError(f"design: rate {rate} Hz leaves fewer than 4 samples after the quiet "
                         "start; raise --rate or the duration")
    if switch_rate is not None and (not np.isfinite(switch_rate) or switch_rate <= 0):
        raise InputError(f"design: switch rate must be > 0 Hz, got {switch_rate}")


def criterion(setting: Setting, t, u, base=None, kind: str = "d-optimal"):
    """The design criterion of the control `u` at the times `t` (`kind`: `"d-optimal"`,
    `log det`, or `"variances"`, `-sum log diag M^-1`) of the vehicle's information
    (relative units) plus `base` (flights flown, prior), and the outputs."""
    M, ys = information(setting, setting.experiment(t, u))
    Mv = vehicle_information(setting, M)
    return objective(kind)(Mv if base is None else Mv + base), ys


def flown_information(setting: Setting, flown: Sequence, grid_rate: float) -> np.ndarray:
    """The vehicle's information (relative units) of the flights already flown: each a
    `Flight` (its cycle-averaged part), an `Experiment` (its time, control column and
    constants), or `(t, u)` of the control."""
    g = len(setting.glob)
    total = np.zeros((g, g))
    for k, item in enumerate(flown or ()):
        if isinstance(item, Flight):
            item = averaged(item, setting.model)
        if isinstance(item, Experiment):
            u = np.asarray(item.u)[:, setting.control]
            consts = {**setting.consts, **{c: v for c, v in item.consts.items()
                                           if c in setting.consts}}
            exp = setting.experiment(np.asarray(item.t), u, consts=consts)
        elif isinstance(item, (tuple, list)) and len(item) == 2:
            exp = setting.experiment(np.asarray(item[0], float), np.asarray(item[1], float))
        else:
            raise InputError(f"design: flown[{k}] is neither an Experiment nor a (t, u) pair")
        M, _ = information(setting, exp)
        total = total + np.asarray(vehicle_information(setting, M))
    return total


def design_input(
    model_or_identification,
    *,
    duration: float = 5.0,
    amplitude: float,
    quiet: float = 1.0,
    parametrisation: str = "steps",
    switch_rate: float = 10.0,
    band: tuple[float, float] = (0.0, 3.0),
    rate: float = 100.0,
    attitude_limit: float | str | None = "3211",
    margin: float = MARGIN,
    hold_other: bool = True,
    flown: Sequence = (),
    prior_information=None,
    model: str | None = None,
    consts=None,
    R=None,
    control: str | None = None,
    attitude: str | None = None,
    restarts: int = 16,
    iterations: int = 300,
    seed: int = 0,
    criterion: str = "variances",
    fast: bool | None = None,
    progress=False,
) -> Design:
    """Design the control input for the next flight (the test-input format).

    Maximises a criterion of the Fisher information `M = sum_k S_k^T R^-1 S_k` of the
    vehicle's free parameters (the Cramer-Rao covariance's inverse, Eqs. 10-11; the
    per-flight biases as nuisance parameters), `S_k` the output sensitivities of the
    identified model simulated with the input. By default the criterion is the geometric mean
    of the parameters' predicted variances (`"variances"`, `-sum log diag M^-1`), the number
    `design.json` and the flights' reports are judged by; `"d-optimal"` (`log det M`) is the
    classic alternative, which spends the flight on the parameters' correlations as much as on
    their variances (on the longitudinal model it gave 1.29-1.30x over a 3211 in the
    geometric-mean std where the variances criterion gave 1.41-1.45x, benchmark
    `benchmarks/design.py`).

    A model whose outputs are affine in the input from rest (the DelFly models: linear
    time-invariant from trim; checked numerically) is simulated once per basis
    signal (each step, or each sine and cosine), and the information is then a quadratic form
    in the input's coefficients; any other model is simulated at every step. The gradient is
    `jax.grad` (through the RK4 solve and its sensitivity equations on the second path); Adam
    (optax) from `restarts` random starts, side by side; a piecewise-constant design is then
    polished as a bang-bang sequence by single sign flips from every restart's end point
    (the criterion is exact and cheap on the first path).

    **Arguments:**
    - `model_or_identification`: a `report.json` (path or dict) of `fwid identify --model
      lon|lat`, an `Identification`, or a `GreyBoxModel` (then `consts=`, `R=`, and
      `control=` / `attitude=` by name).
    - `duration` [s], `amplitude` [rad], `quiet` [s]: the input's length, peak and the
      quiet start (zero input) for the trim estimate.
    - `parametrisation`: `"multisine"` (free amplitudes and phases of the harmonics of
      `1 / (duration - quiet)` in `band` Hz) or `"steps"` (piecewise constant, switching at
      `switch_rate` Hz).
    - `rate` [Hz]: the input's sample rate (the information is that of data at this rate).
    - `attitude_limit` [rad]: the attitude excursion (theta for `lon`, phi for `lat`) the
      model's prediction must keep within `margin * attitude_limit`: the input is scaled
      down to it inside the criterion (exact for a model linear in the input), with a
      penalty and a final scaling for one that is not. `"3211"` (default): within the
      excursion the model predicts for the 3211 of the same amplitude and length (the
      input it replaces, so no excursion the pilot would not already fly; at the peak
      amplitude it is hardly binding: relaxed, the designed std improved by 1-2 %, for
      8-10 % more attitude excursion); `None`: no bound.
    - `hold_other`: the other axis's control is held at zero (recorded in the limits).
    - `flown`: flights already flown (`Flight`s, `Experiment`s or `(t, u)` pairs of the
      control): their information, predicted by the model for their inputs, adds (campaign
      planning, flight by flight).
    - `prior_information`: a prior on the vehicle's parameters, `{name: std}` or an
      information matrix in their units; default: the prior of the report's fit, if any.
    - `criterion`: `"variances"` (default) or `"d-optimal"`, as above.
    - `fast`: `None` (default) designs through the precomputed responses where the model is
      affine in the input and through the simulation otherwise; `False` always through the
      simulation; `True` requires the former (`InputError` if the check fails).
    - `progress`: `True` prints a progress line per 50 steps.

    **Returns:** a [`fwid.design.Design`][].
    """
    if parametrisation not in ("multisine", "steps"):
        raise InputError(f"design: parametrisation must be 'multisine' or 'steps', got "
                         f"{parametrisation!r}")
    check_limits(duration, amplitude, quiet, rate, switch_rate)
    mdl, cst, Rm, noise = _source(model_or_identification, model, consts, R)
    mdl = mdl.with_params({k: 0.0 for k in mdl.local})
    control = control or CONTROL.get(mdl.name, mdl.inputs[0])
    if control not in mdl.inputs:
        raise InputError(f"design: the model has no input {control!r} ({', '.join(mdl.inputs)})")
    attitude = attitude or ATTITUDE.get(mdl.name)
    att = mdl.outputs.index(attitude) if attitude in mdl.outputs else None
    setting = Setting(mdl, cst, Rm, control)
    grid = Grid(duration, quiet, rate)
    if prior_information is None and isinstance(model_or_identification, (str, dict)):
        prior_information = report_prior(model_or_identification)  # the fit's own prior
    if isinstance(prior_information, dict):  # only the vehicle's parameters
        vehicle = {setting.names[i] for i in setting.glob}
        prior_information = {k: v for k, v in prior_information.items() if k in vehicle} or None
    prior = prior_matrix(setting, prior_information)
    base = flown_information(setting, flown, rate) + prior
    if att is None or attitude_limit is None:
        bound = None
    elif attitude_limit == "3211":  # no more than the 3211 of the same amplitude would do
        _, y3 = simulate(mdl, setting.experiment(grid.t, input_3211(grid, amplitude)))
        bound = float(np.max(np.abs(np.asarray(y3)[:, att])))
    else:
        if not np.isfinite(attitude_limit) or attitude_limit <= 0:
            raise InputError(f"design: attitude limit must be > 0 rad, got {attitude_limit}")
        bound = margin * float(attitude_limit)

    basis, coef, start = _parametrisation(parametrisation, grid, amplitude, switch_rate,
                                          band)
    k = basis.shape[0]
    E = jnp.asarray(basis)

    def signal(x):
        return coef(x) @ E

    affine, worst = (None, None) if fast is False else affine_responses(
        setting, grid.t, basis, amplitude, seed)
    if fast is True and affine is None:
        raise InputError(f"design: fast=True but the model is not affine in the input (a "
                         f"direct solve differs from the affine prediction by {worst:.2g}, "
                         "relative); leave fast to None")
    crit = objective(criterion)

    if affine is not None:  # the information is a quadratic form in the coefficients
        loss = AffineLoss(affine, coef, jnp.asarray(base),
                          jnp.asarray(1.0 if bound is None else bound),
                          None if bound is None else att, setting.glob, setting.loc,
                          criterion)
    else:
        def bounded(u):
            """`u` scaled down so that the predicted attitude peak is within the bound (exact
            for a model linear in the input from trim; `_within_attitude` finishes
            otherwise)."""
            if bound is None:
                return u
            _, ys = simulate(mdl, setting.experiment(grid.t, u))
            peak = jnp.max(jnp.abs(ys[:, att]))
            return u * jnp.where(jnp.isfinite(peak), jnp.minimum(1.0, bound / peak), 0.0)

        def loss(x):
            M, ys = information(setting, setting.experiment(grid.t, bounded(signal(x))))
            c = crit(vehicle_information(setting, M) + base)
            pen = 0.0
            if bound is not None:  # the rest of the way for a model nonlinear in the input
                pen = PENALTY * jnp.mean(jax.nn.relu(jnp.abs(ys[:, att]) / bound - 1.0) ** 2)
            return -c + pen

    starts = jax.vmap(start)(jax.random.split(jax.random.PRNGKey(seed), restarts))
    _say(progress, f"design: {parametrisation}, {k} variables, {restarts} restarts, "
                   f"{grid.t.size} samples, "
                   + ("through the model's precomputed responses (affine in the input)"
                      if affine is not None else "through the simulation at every step"))
    xs, fs, history = minimise(loss, starts, iterations=iterations,
                               learning_rate=0.05 if parametrisation == "multisine" else 0.1,
                               progress=progress)
    best, polished = xs[int(np.argmin(fs))], None
    if affine is not None and parametrisation == "steps":  # the optimum is near bang-bang
        f_best = float(np.min(fs))
        for x in xs:  # every restart's, the search being local
            xb, fb, flips = flip_search(loss, x)
            if fb < f_best:
                best, f_best, polished = xb, fb, flips
        _say(progress, f"design: bang-bang polish of every restart (sign flips), best "
                       f"criterion {-f_best:.4g}")
    u = np.asarray(signal(jnp.asarray(best)))
    u = _within_attitude(setting, grid, u, att, bound)
    return _result(setting, grid, u, base, att, bound, amplitude, attitude_limit, margin,
                   hold_other, crit, dict(model=mdl.name, criterion=criterion,
                                    affine_in_input=affine is not None,
                                    affine_check_rel=worst, parametrisation=parametrisation,
                                    switch_rate=switch_rate if parametrisation == "steps"
                                    else None, band_hz=list(band) if parametrisation ==
                                    "multisine" else None, restarts=restarts,
                                    iterations=iterations, seed=seed, rate_hz=rate,
                                    noise=noise, flown=len(flown or ()),
                                    prior=prior_information is not None,
                                    sign_flips=polished,
                                    history=[-h for h in history]))


def _within_attitude(setting, grid, u, att, bound, tries: int = 5) -> np.ndarray:
    """Scale `u` down until the predicted attitude excursion is within `bound` (exact in one
    step for a model linear in the input from trim)."""
    if bound is None:
        return u
    for _ in range(tries):
        _, ys = information(setting, setting.experiment(grid.t, u))
        peak = float(np.max(np.abs(np.asarray(ys)[:, att])))
        if peak <= bound * (1 + 1e-9):
            break
        u = u * (bound / peak) * (1 - 1e-6)
    return u


def _result(setting, grid, u, base, att, bound, amplitude, attitude_limit, margin,
            hold_other, objective, settings) -> Design:
    g = np.asarray(setting.glob)

    def evaluate(sig):
        M, ys = information(setting, setting.experiment(grid.t, sig))
        Mv = np.asarray(vehicle_information(setting, M)) + base
        std = np.sqrt(np.diag(np.linalg.inv(np.asarray(M)))) * np.asarray(setting.scale)
        std[g] = np.sqrt(np.diag(np.linalg.inv(Mv))) * np.asarray(setting.scale)[g]
        return Mv, np.asarray(ys), std, float(objective(jnp.asarray(Mv)))

    u3211 = input_3211(grid, amplitude)
    Mv, ys, std, crit = evaluate(jnp.asarray(u))
    Mv3, ys3, std3, crit3 = evaluate(jnp.asarray(u3211))

    def peak(y):
        return None if att is None else float(np.max(np.abs(y[:, att])))

    limits = {"amplitude_rad": amplitude, "peak_rad": float(np.max(np.abs(u))),
              "duration_s": grid.duration, "quiet_s": grid.quiet,
              "attitude": None if att is None else setting.model.outputs[att],
              "attitude_limit_rad": attitude_limit, "margin": margin,
              "attitude_bound_rad": bound, "attitude_peak_rad": peak(ys),
              "attitude_peak_3211_rad": peak(ys3), "other_control_held": bool(hold_other)}
    names = setting.names
    return Design(
        t=grid.t, u=np.asarray(u), control=setting.model.inputs[setting.control],
        outputs=setting.model.outputs, response=ys, names=names, std=std, std_3211=std3,
        ratio=std3 / std, vehicle_names=tuple(names[i] for i in g),
        information=absolute(setting, Mv, g), information_3211=absolute(setting, Mv3, g),
        criterion=crit, criterion_3211=crit3, u_3211=u3211, response_3211=ys3,
        limits=limits, settings=settings)
