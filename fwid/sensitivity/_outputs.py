"""Derivatives of the simulated outputs `y(t_k)` (Eq. 7 integrated by RK4, Sec. IV.B) with
respect to the parameters, the per-flight constants or the initial state."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from jaxtyping import Array, Float

from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ._common import _WRT, _check_single, _full_params, _pick_names, output_jacobian


def output_sensitivity(
    model: GreyBoxModel,
    exp: Experiment,
    params: Mapping[str, float] | None = None,
    *,
    wrt: str = "params",
    names: Sequence[str] | None = None,
) -> dict[str, Float[Array, "n ny"]]:
    """Derivatives of the simulated outputs `y(t_k)`, by forward-mode autodiff.

    With respect to the parameters, the per-flight constants or the initial state.

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
    S = fwid.output_sensitivity(model, exp)          # {"Mq": (n, 4), ...}
    S_trim = fwid.output_sensitivity(model, exp, wrt="consts", names=["theta0"])
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
    _, S = output_jacobian(model, exp, p, names, wrt)
    return {k: S[k] for k in names}  # in the order asked for (jit returns sorted keys)
