"""The information of a model whose outputs are affine in the input: precomputed once.

The DelFly grey-box models are linear time-invariant in the perturbation states and the
input, from trim (Eq. 7, Eq. 8). Simulated from rest (`x0 = 0`, the biases at zero), their
outputs are linear in the input, and the output sensitivities `S = dy / dtheta` are affine in
it: the sensitivity equations `dS/dt = A S + dA/dtheta x + dB/dtheta u + db/dtheta` are
driven by the state and the input (linear in `u`) and by the bias terms (independent of
`u`). The classical RK4 steps and the linear interpolation of the input between samples are
linear too, so the same holds for the simulated numbers, to round-off. An input that is a
combination `u = sum_j v_j e_j` of fixed signals `e_j` (the steps of a piecewise-constant
sequence, the sines and cosines of a multisine) then has

    S(v) = S_0 + sum_j v_j H_j,    y(v) = sum_j v_j Y_j,

`S_0` the sensitivities of the zero input (the biases' alone) and `H_j`, `Y_j` those of each
`e_j`. They are simulated once (`k + 1` solves side by side), and the information
`M(v) = S(v)^T R^-1 S(v)` is a quadratic form in `v`: the design's steps cost no simulation.

Whether a model is affine in the input is checked numerically on the same solves (no model
property is trusted): two random combinations at the design's amplitude, one at full scale
and one at `-0.3` of another, simulated directly, must equal their affine prediction to
`AFFINE_RTOL` of their size. A model that fails (a nonlinear one, a nonzero start or bias)
is designed through the simulation at every step ([`fwid.design_input`][] falls back).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._information import Setting, sensitivities

#: The largest relative difference between a direct solve and the affine prediction for the
#: model to count as affine in the input (round-off of a linear model is ~1e-13).
AFFINE_RTOL = 1e-7


class Affine(eqx.Module):
    """The precomputed responses of a model affine in the input.

    **Fields:**
    - `s0`: the whitened sensitivities of the zero input, `(n * outputs, p)`;
    - `h`: the whitened sensitivities of each basis signal (per unit coefficient),
      `(k, n * outputs, p)`;
    - `y`: the outputs of each basis signal (per unit coefficient), `(k, n, outputs)`;
    - `gram`: `G_ab = A_a^T A_b` of `A = (s0, h_1, ..., h_k)`, `(k + 1, k + 1, p, p)`, so
      that `M(v) = sum_ab w_a w_b G_ab` with `w = (1, v)`; `None` where it would be larger
      than `h` (`(k + 1) p > n * outputs`), and `M` is formed from the sensitivities.
    """

    s0: Float[Array, "N p"]
    h: Float[Array, "k N p"]
    y: Float[Array, "k n ny"]
    gram: Float[Array, "k1 k1 p p"] | None = None

    def jacobian(self, v: Float[Array, " k"]) -> Float[Array, "N p"]:
        """The whitened sensitivities of the input `sum_j v_j e_j`."""
        return self.s0 + jnp.tensordot(v, self.h, axes=1)

    def information(self, v: Float[Array, " k"]) -> Float[Array, "p p"]:
        """The information matrix `M` (relative parameters) of the input `sum_j v_j e_j`."""
        if self.gram is not None:
            w = jnp.concatenate([jnp.ones(1, dtype=v.dtype), v])
            return jnp.einsum("a,abpq,b->pq", w, self.gram, w)
        J = self.jacobian(v)
        return J.T @ J

    def outputs(self, v: Float[Array, " k"]) -> Float[Array, "n ny"]:
        """The predicted outputs of the input `sum_j v_j e_j`."""
        return jnp.tensordot(v, self.y, axes=1)


@eqx.filter_jit
def _solves(setting: Setting, exp, signals):
    def one(u):
        e = eqx.tree_at(lambda e: e.u, exp, exp.u.at[:, setting.control].set(u))
        ys, S = sensitivities(setting, e)
        return ys, jnp.einsum("ab,nbp->nap", setting.whiten, S)
    return jax.vmap(one)(signals)


def affine_responses(setting: Setting, t, basis: np.ndarray, scale: float,
                     seed: int = 0) -> tuple[Affine | None, float]:
    """The responses of the model to each basis signal, if the model is affine in the input.

    **Arguments:**
    - `setting`: the model at its estimate, from rest; `t`: the sample times.
    - `basis`: the basis signals `e_j`, `(k, n)`.
    - `scale`: the size of the coefficients the design uses (its amplitude): the basis is
      simulated at this size and the check is made there.
    - `seed`: of the check's random combinations.

    **Returns:** the [`Affine`][] responses (`None` where the check fails) and the check's
    largest relative difference.
    """
    basis = np.asarray(basis, dtype=float)
    k, n = basis.shape
    rng = np.random.default_rng(seed)
    v1, v2 = rng.uniform(-1.0, 1.0, (2, k))
    tests = np.stack([v1 @ basis, -0.3 * (v2 @ basis)])
    peak = np.max(np.abs(tests), axis=1, keepdims=True)
    peak = np.where(peak > 0, peak, 1.0)
    coef = scale * np.stack([v1, -0.3 * v2]) / peak
    tests = coef @ basis
    signals = np.concatenate([np.zeros((1, n)), scale * basis, tests])
    ys, Sw = _solves(setting, setting.experiment(t, np.zeros(n)), jnp.asarray(signals))
    ys, Sw = np.asarray(ys), np.asarray(Sw)
    N = Sw.shape[1] * Sw.shape[2]
    s0 = Sw[0].reshape(N, -1)
    h = (Sw[1:k + 1].reshape(k, N, -1) - s0[None]) / scale
    y = (ys[1:k + 1] - ys[0][None]) / scale
    worst = 0.0
    for c, yt, St in zip(coef, ys[k + 1:], Sw[k + 1:]):
        dS = St.reshape(N, -1) - s0
        pS = np.tensordot(c, h, axes=1)
        py = np.tensordot(c, y, axes=1) + ys[0]
        size = max(np.max(np.abs(dS)), 1e-300)
        worst = max(worst, float(np.max(np.abs(dS - pS)) / size),
                    float(np.max(np.abs(yt - py)) / max(np.max(np.abs(yt)), 1e-300)))
    if not np.isfinite(worst) or worst > AFFINE_RTOL or np.max(np.abs(ys[0])) > 0:
        return None, worst
    gram = None
    if (k + 1) * s0.shape[1] <= N:
        A = np.concatenate([s0[None], h])
        gram = jnp.asarray(np.einsum("anp,bnq->abpq", A, A, optimize=True))
    return Affine(jnp.asarray(s0), jnp.asarray(h), jnp.asarray(y), gram), worst
