"""The Fisher information of an output-error fit as a function of the input signal.

`M = sum_k S_k^T R^-1 S_k` (the inverse of the Cramer-Rao covariance, Eqs. 10-11 at the
estimate), `S_k = dy_k / dtheta` the output sensitivities of the model simulated with the
input (forward sensitivity equations, [`simulate_sensitivities`][]). The parameters are taken
relative to their values (`theta = theta0 (1 + s)`, a unit scale where `theta0 = 0`), so that
`M` is well scaled; `log det` changes only by a constant.

The per-flight parameters (`model.local`, the bias terms) are nuisance parameters: each
flight has its own. What one flight tells about the vehicle's parameters is the Schur
complement `M_gg - M_gl M_ll^-1 M_lg`; these add over flights and with a prior.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..estimate._uncertainty import fisher_information
from ..models._greybox import GreyBoxModel
from ..simulation._experiment import Experiment
from ..simulation._simulate import simulate_sensitivities


class Setting(eqx.Module):
    """What the information of an input needs: the identified model (at its estimate, the
    flight at trim), the constants, the noise and the parameter scales.

    **Fields:** `model`, `consts`, `whiten` (`W` with `W^T W = R^-1`), `scale` (of each free
    parameter), `control` (the column of the designed input among `model.inputs`),
    `glob` / `loc` (indices of the vehicle's and the per-flight free parameters).
    """

    model: GreyBoxModel
    consts: dict
    whiten: Float[Array, "ny ny"]
    scale: Float[Array, " p"]
    control: int = eqx.field(static=True)
    glob: tuple[int, ...] = eqx.field(static=True)
    loc: tuple[int, ...] = eqx.field(static=True)

    def __init__(self, model: GreyBoxModel, consts, R, control: str | None = None):
        self.model = model
        self.consts = {k: jnp.asarray(v, dtype=float) for k, v in dict(consts).items()}
        R = np.atleast_2d(np.asarray(R, dtype=float))
        self.whiten = jnp.asarray(np.linalg.cholesky(np.linalg.inv(R)).T)
        theta = np.asarray(model.theta())
        self.scale = jnp.asarray(np.where(np.abs(theta) > 0, np.abs(theta), 1.0))
        self.control = model.inputs.index(control) if control else 0
        self.glob = tuple(i for i, k in enumerate(model.free) if k not in model.local)
        self.loc = tuple(i for i, k in enumerate(model.free) if k in model.local)

    @property
    def names(self) -> tuple[str, ...]:
        return self.model.free

    def experiment(self, t, u, x0=None, consts=None) -> Experiment:
        """The experiment of the control `u` (the model's other inputs held at zero)."""
        nu = len(self.model.inputs)
        uu = jnp.zeros((len(t), nu)).at[:, self.control].set(u)
        return Experiment(np.asarray(t), uu, jnp.zeros((len(t), len(self.model.outputs))),
                          x0=jnp.zeros(len(self.model.states)) if x0 is None else x0,
                          consts=self.consts if consts is None else consts,
                          mask=np.ones(len(t)))


def sensitivities(setting: Setting, exp: Experiment
                  ) -> tuple[Float[Array, "n ny"], Float[Array, "n ny p"]]:
    """The outputs and their derivatives by the relative parameters."""
    model = setting.model
    theta0 = model.theta()

    def params_of(s):
        return model.merge(theta0 + setting.scale * s)

    ys, S = simulate_sensitivities(model, exp, params_of, jnp.zeros_like(theta0))
    return ys, S


@eqx.filter_jit
def information(setting: Setting, exp: Experiment
                ) -> tuple[Float[Array, "p p"], Float[Array, "n ny"]]:
    """The information matrix `M` (relative parameters) of one flight and its outputs
    (compiled once per model and length)."""
    ys, S = sensitivities(setting, exp)
    J = jnp.einsum("ab,nbp->nap", setting.whiten, S * exp.mask[:, None, None])
    return fisher_information(J.reshape(-1, J.shape[-1])), ys


def vehicle_information(setting: Setting, M: Float[Array, "p p"]) -> Float[Array, "g g"]:
    """The Schur complement of the per-flight parameters: what a flight tells about the
    vehicle's parameters."""
    return schur(M, setting.glob, setting.loc)


def schur(M: Float[Array, "p p"], glob, loc) -> Float[Array, "g g"]:
    """`M_gg - M_gl M_ll^-1 M_lg` of the indices `glob` (kept) and `loc` (eliminated)."""
    g, l_ = np.asarray(glob), np.asarray(loc)
    Mgg = M[np.ix_(g, g)]
    if l_.size == 0:
        return Mgg
    Mgl, Mll = M[np.ix_(g, l_)], M[np.ix_(l_, l_)]
    # a small ridge keeps M_ll invertible for an input of zero (the quiet start alone)
    ridge = 1e-12 * jnp.trace(Mll) / l_.size + 1e-300
    return Mgg - Mgl @ jnp.linalg.solve(Mll + ridge * jnp.eye(l_.size), Mgl.T)


def log_det(M: Float[Array, "g g"]) -> Float[Array, ""]:
    """`log det M` of a symmetric positive-definite `M` (Cholesky)."""
    L = jnp.linalg.cholesky(0.5 * (M + M.T))
    return 2.0 * jnp.sum(jnp.log(jnp.diag(L)))


def absolute(setting: Setting, M: Float[Array, "p p"], idx=None) -> np.ndarray:
    """`M` of the relative parameters `idx` back in the parameters' own units."""
    s = np.asarray(setting.scale) if idx is None else np.asarray(setting.scale)[np.asarray(idx)]
    return np.asarray(M) / np.outer(s, s)


def prior_matrix(setting: Setting, prior) -> np.ndarray:
    """A prior on the vehicle's parameters as information in relative units: `prior` a dict
    `{name: std}` (independent), or a matrix over the vehicle's free parameters in their own
    units, or `None`."""
    g = len(setting.glob)
    if prior is None:
        return np.zeros((g, g))
    names = [setting.names[i] for i in setting.glob]
    s = np.asarray(setting.scale)[np.asarray(setting.glob)]
    if isinstance(prior, dict):
        unknown = [k for k in prior if k not in names]
        if unknown:
            from .._errors import InputError
            raise InputError(f"design: prior on unknown parameters {unknown}; the vehicle's "
                             f"free parameters are {', '.join(names)}")
        d = np.array([1.0 / float(prior[k]) ** 2 if k in prior else 0.0 for k in names])
        P = np.diag(d)
    else:
        P = np.asarray(prior, dtype=float)
        if P.shape != (g, g):
            from .._errors import InputError
            raise InputError(f"design: prior_information must be {g} x {g} (the parameters "
                             f"{', '.join(names)}), got {P.shape}")
    return P * np.outer(s, s)
