"""The time-varying (flapping) aerodynamics: a Fourier series in the flapping phase, Eq. (12).

$$F_{TV}(t) = \\sum_{n=1}^{h} a_n \\sin(n \\varphi(t)) + b_n \\cos(n \\varphi(t)),
\\qquad \\varphi(t) = \\int_0^t 2 \\pi f(s)\\, ds$$

The paper writes `2 pi n f t` with the measured flapping frequency `f`; fwid drives the series
with the flapping *phase* (see [`fwid.decomposition.flapping_phase`][]), which is the same for a
constant `f` and stays in step with the wing beat when `f` drifts.

The model is a static input-output [`fwid.GreyBoxModel`][] (no states): input `phase`,
outputs the force and moment channels, parameters `a<o><n>` (sine) and `b<o><n>` (cosine) for
output `o` (lower case) and harmonic `n` (the report format: `ax1 bx1 ... am3 bm3`).
[`fwid.fit`][] estimates it by output-error ML (no integration needed), started from
[`fwid.models.fourier_least_squares`][].
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ._greybox import GreyBoxModel

#: Outputs of the longitudinal and lateral flapping models.
LON_OUTPUTS = ("X", "Z", "M")
LAT_OUTPUTS = ("Y", "L", "N")


def fourier_param_names(outputs: Sequence[str], harmonics: int = 3) -> tuple[str, ...]:
    """Parameter names of Eq. (12) in Table 7's order: `ax1 bx1 ax2 bx2 ax3 bx3 az1 ...`."""
    return tuple(
        f"{ab}{o.lower()}{n}" for o in outputs for n in range(1, harmonics + 1) for ab in "ab"
    )


def _coefficient_arrays(p: Mapping, outputs, harmonics):
    """`(A, B)`, each `(outputs, harmonics)`: the sine and cosine coefficients."""
    A = jnp.stack([jnp.stack([p[f"a{o.lower()}{n}"] for n in range(1, harmonics + 1)])
                   for o in outputs])
    B = jnp.stack([jnp.stack([p[f"b{o.lower()}{n}"] for n in range(1, harmonics + 1)])
                   for o in outputs])
    return A, B


def fourier_series(
    phase: Float[ArrayLike, "*n"],
    params: Mapping[str, Float[ArrayLike, ""]],
    outputs: Sequence[str] = LON_OUTPUTS,
    harmonics: int = 3,
) -> Float[Array, "*n outputs"]:
    """Evaluate Eq. (12) at the flapping phase `phase`.

    **Arguments:**
    - `phase`: the flapping phase [rad], any shape.
    - `params`: the coefficients `a<o><n>`, `b<o><n>` (extra keys ignored).
    - `outputs`, `harmonics`: which channels, how many harmonics.

    **Returns:** the time-varying forces/moments, shape `phase.shape + (len(outputs),)`.
    """
    phase = jnp.asarray(phase, dtype=float)
    A, B = _coefficient_arrays(params, outputs, harmonics)
    n = jnp.arange(1, harmonics + 1, dtype=float)
    arg = phase[..., None] * n  # (*n, h)
    return jnp.sin(arg) @ A.T + jnp.cos(arg) @ B.T


def fourier_regressors(phase: Float[ArrayLike, " n"], harmonics: int = 3) -> np.ndarray:
    """The regression matrix of Eq. (12), `[sin(phi), cos(phi), sin(2 phi), cos(2 phi), ...]`,
    shape `(n, 2 harmonics)`, in the order of [`fwid.models.fourier_param_names`][]."""
    phase = np.asarray(phase, dtype=float)
    cols = []
    for n in range(1, harmonics + 1):
        cols += [np.sin(n * phase), np.cos(n * phase)]
    return np.stack(cols, axis=-1)


def _no_states(x, u, p, c):
    return jnp.zeros(0)


def fourier_model(
    outputs: Sequence[str] = LON_OUTPUTS,
    harmonics: int = 3,
    params: Mapping[str, float] | None = None,
    *,
    name: str = "flap",
) -> GreyBoxModel:
    """The Fourier-series model of the flapping aerodynamics, Eq. (12), as a static model.

    **Arguments:**
    - `outputs`: the force/moment channels (longitudinal `X Z M` by default; `Y L N` for the
      lateral one, or any subset).
    - `harmonics`: the number of harmonics `h` (the paper: 3).
    - `params`: start values (default: all coefficients zero).
    - `name`: the model's name in reports.

    **Returns:** a [`fwid.GreyBoxModel`][] with `states=()`, `inputs=("phase",)`, outputs
    `outputs`; build its [`fwid.Experiment`][] with `x0=np.zeros(0)`.
    """
    outputs = tuple(outputs)
    if harmonics < 1:
        raise ValueError(f"fourier_model: harmonics must be at least 1, got {harmonics}")
    names = fourier_param_names(outputs, harmonics)
    unknown = sorted(set(params or {}) - set(names))
    if unknown:
        raise ValueError(f"fourier_model: {unknown} are not coefficients of this series "
                         f"({', '.join(names)})")
    p = dict.fromkeys(names, 0.0)
    p.update(params or {})

    # An output function equal (and hashing equal) per (outputs, harmonics), not a fresh
    # closure: equal models then reuse the compiled fit.
    h = _output_function(outputs, harmonics)
    return GreyBoxModel(_no_states, states=(), inputs=("phase",), params=p, h=h,
                        outputs=outputs, name=name)


class _FourierOutput:
    """`h(x, u, p, c)` of the Fourier model; equal (and hashing equal) per configuration."""

    def __init__(self, outputs: tuple[str, ...], harmonics: int):
        self.outputs = outputs
        self.harmonics = harmonics

    def __call__(self, x, u, p, c):
        return fourier_series(u[0], p, self.outputs, self.harmonics)

    def __eq__(self, other):
        return (isinstance(other, _FourierOutput) and other.outputs == self.outputs
                and other.harmonics == self.harmonics)

    def __hash__(self):
        return hash((_FourierOutput, self.outputs, self.harmonics))


def _output_function(outputs, harmonics) -> _FourierOutput:
    return _FourierOutput(tuple(outputs), int(harmonics))


def fourier_structure(model: GreyBoxModel) -> tuple[tuple[str, ...], int]:
    """`(outputs, harmonics)` of a model built by [`fwid.models.fourier_model`][]."""
    if not isinstance(model.h, _FourierOutput):
        raise ValueError(f"model {model.name!r} is not a Fourier-series model (Eq. 12)")
    return model.h.outputs, model.h.harmonics


def fourier_least_squares(
    model: GreyBoxModel,
    experiments,
) -> GreyBoxModel:
    """Ordinary least-squares estimate of the Fourier coefficients (the start of the ML fit).

    Eq. (12) is linear in its coefficients, so each output is regressed on the harmonic
    regressors of the phase (Section V.A: "initial guesses ... determined using an ordinary
    least-squares estimator"); several experiments are stacked (padding masked out).

    **Arguments:**
    - `model`: a model from [`fwid.models.fourier_model`][].
    - `experiments`: one [`fwid.Experiment`][] or a list of them (input `phase`, outputs the
      measured flapping forces).

    **Returns:** the model with its free coefficients set to the least-squares values.
    """
    outputs, harmonics = fourier_structure(model)
    exps = experiments if isinstance(experiments, (list, tuple)) else [experiments]
    Phi, Z = [], []
    for e in exps:
        keep = np.asarray(e.mask) > 0
        Phi.append(fourier_regressors(np.asarray(e.u)[keep, 0], harmonics))
        Z.append(np.asarray(e.z)[keep])
    Phi, Z = np.concatenate(Phi), np.concatenate(Z)
    coef, *_ = np.linalg.lstsq(Phi, Z, rcond=None)  # (2h, outputs)
    values = {}
    for j, o in enumerate(outputs):
        for n in range(1, harmonics + 1):
            values[f"a{o.lower()}{n}"] = coef[2 * (n - 1), j]
            values[f"b{o.lower()}{n}"] = coef[2 * (n - 1) + 1, j]
    return model.with_params({k: v for k, v in values.items() if k in model.free})


def shift_phase(
    params: Mapping[str, float], offset: float, outputs: Sequence[str] = LON_OUTPUTS,
    harmonics: int = 3,
) -> dict[str, float]:
    """The coefficients of the same Fourier series advanced by `offset` in phase (Section V.A).

    `a_n sin(n(phi + d)) + b_n cos(n(phi + d)) = a'_n sin(n phi) + b'_n cos(n phi)` with
    `a'_n = a_n cos(n d) - b_n sin(n d)`, `b'_n = a_n sin(n d) + b_n cos(n d)`: the model
    aligned with a flight that starts `offset` radians later in the stroke.

    **Arguments:**

    - `params`: the coefficients `ax1, bx1, ...` by name (Eq. 12).
    - `offset`: the phase advance `d` [rad].
    - `outputs`: the outputs whose series are rotated (default `X Z M`).
    - `harmonics`: the number of harmonics (default 3).

    **Returns:** the rotated coefficients by name.
    """
    out = {}
    for o in outputs:
        for n in range(1, harmonics + 1):
            a, b = float(params[f"a{o.lower()}{n}"]), float(params[f"b{o.lower()}{n}"])
            c, s = np.cos(n * offset), np.sin(n * offset)
            out[f"a{o.lower()}{n}"] = a * c - b * s
            out[f"b{o.lower()}{n}"] = a * s + b * c
    return out


def estimate_phase_offset(
    model: GreyBoxModel,
    phase: Float[ArrayLike, " n"],
    z: Float[ArrayLike, "n outputs"],
    *,
    grid: int = 1440,
) -> float:
    """The phase offset that best aligns the Fourier model with a flight (Section V.A).

    A validation flight starts at another point of the stroke than the estimation flight, so
    its measured phase (integrated from its own start) is off by a constant. The offset `d`
    minimises `sum_j sum_k (z_jk - F_j(phi_k + d))^2 / var(z_j)` over all outputs (each
    weighted by its variance, so forces and moments count alike): a fine grid over one
    period, then Newton steps. The cost is exact and cheap through the normal equations.

    **Arguments:**
    - `model`: the identified Fourier model.
    - `phase`: the flight's flapping phase [rad] (integral of `2 pi f` from its start).
    - `z`: the flight's measured flapping forces, `(n, outputs)` in the model's output order.
    - `grid`: number of grid points over `[0, 2 pi)`.

    **Returns:** the offset `d` in `[-pi, pi)` [rad]; the aligned model is
    `model.with_params(shift_phase(model.params, d, ...))`.
    """
    outputs, harmonics = fourier_structure(model)
    Phi = fourier_regressors(phase, harmonics)
    z = np.asarray(z, dtype=float)
    w = 1.0 / np.maximum(z.var(axis=0), 1e-300)
    G = Phi.T @ Phi  # (2h, 2h)
    g = Phi.T @ z  # (2h, ny)
    A, B = (np.asarray(a) for a in _coefficient_arrays(model.params, outputs, harmonics))
    n = np.arange(1, harmonics + 1)

    def coeffs(d):
        """Rotated coefficient matrix `(..., 2h, ny)` for offsets `d` of shape `(...)`."""
        d = np.asarray(d, dtype=float)[..., None, None]
        c, s = np.cos(n[:, None] * d), np.sin(n[:, None] * d)  # (..., h, 1)
        a2 = A.T * c - B.T * s  # (..., h, ny)
        b2 = A.T * s + B.T * c
        return np.stack([a2, b2], axis=-2).reshape(*a2.shape[:-2], 2 * harmonics, A.shape[0])

    def cost(d):
        C = coeffs(d)
        quad = np.einsum("...ij,ik,...kj->...j", C, G, C)
        lin = np.einsum("...ij,ij->...j", C, g)
        return np.sum(w * (quad - 2 * lin), axis=-1)

    ds = np.linspace(-np.pi, np.pi, grid, endpoint=False)
    d = ds[np.argmin(cost(ds))]
    h = 1e-4
    for _ in range(8):  # Newton on the smooth periodic cost, finite-difference derivatives
        c0, cp, cm = cost(d), cost(d + h), cost(d - h)
        d2 = (cp - 2 * c0 + cm) / h**2
        if not d2 > 0:
            break
        step = -(cp - cm) / (2 * h) / d2
        step = float(np.clip(step, -np.pi / grid, np.pi / grid))
        d += step
        if abs(step) < 1e-12:
            break
    return float((d + np.pi) % (2 * np.pi) - np.pi)
