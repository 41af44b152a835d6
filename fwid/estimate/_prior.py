"""What is known before the flight: a Gaussian prior on the parameters and bounds on them.

A prior `{name: (mean, std)}` (from an earlier identification, [`prior_from`][], or a wind
tunnel) enters the output-error cost as one extra residual per parameter,
`r_i = (theta_i - mean_i) / std_i` (Jategaonkar 2015, Sec. 4.17, "a priori information":
maximum a posteriori instead of maximum likelihood):

    J(theta) = Eq. (10) + 1/2 sum_i r_i^2,

consistently in the Gauss-Newton step (`H + W^2`, `g + W^2 (theta - mean)`,
`W = diag(1/std)`), in the cost the step halving compares, and in the information matrix
(`M = M_data + W^2`) behind the standard deviations. Bounds `{name: (low, high)}` (`None`
an open side) are kept by the bounded-variable Gauss-Newton step of
`fwid.estimate._gauss_newton` (Jategaonkar 2015, Sec. 4.13.3).

Both live in the solver as [`PriorBounds`][]: four arrays over the free vector, so one
compiled program serves every prior and every set of bounds (an entry without a prior has
weight 0, an open side an infinite bound; then the arithmetic is exactly that of the plain
fit).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._errors import InputError


class PriorBounds(eqx.Module):
    """The prior and the bounds over the free vector `theta` (`p` entries).

    **Fields:**
    - `mean`: the prior means (0 where there is no prior).
    - `weight`: `1 / std` of the prior (0 where there is none).
    - `lower`, `upper`: the bounds (`-inf`, `+inf` where open).
    """

    mean: Float[Array, " p"]
    weight: Float[Array, " p"]
    lower: Float[Array, " p"]
    upper: Float[Array, " p"]

    @classmethod
    def none(cls, p: int) -> "PriorBounds":
        """No prior and no bounds on `p` parameters."""
        inf = jnp.full(p, jnp.inf)
        return cls(mean=jnp.zeros(p), weight=jnp.zeros(p), lower=-inf, upper=inf)

    def residuals(self, theta):
        """The prior's residuals `(theta - mean) / std` (their Jacobian is `diag(weight)`)."""
        return self.weight * (theta - self.mean)

    def cost(self, theta):
        """The prior's part of the cost, `1/2 sum ((theta - mean) / std)^2`."""
        return 0.5 * jnp.sum(self.residuals(theta) ** 2)

    def add_terms(self, H, g, theta):
        """`(H + W^2, g + W^2 (theta - mean))`: the prior's residuals added to the
        Gauss-Newton Hessian `H` and the gradient `g` of the data's cost."""
        w2 = self.weight**2
        return H + jnp.diag(w2), g + w2 * (theta - self.mean)

    def information(self):
        """The prior's information matrix `W^2 = diag(1 / std^2)`."""
        return jnp.diag(self.weight**2)

    def clip(self, theta):
        """`theta` moved into the bounds."""
        return jnp.clip(theta, self.lower, self.upper)


def _pair(what: str, name: str, value, keys: tuple[str, str]):
    """`(a, b)` from `(a, b)`, `[a, b]` or `{keys[0]: a, keys[1]: b}` (a missing key `None`)."""
    if isinstance(value, Mapping):
        extra = [k for k in value if k not in keys]
        if extra:
            raise InputError(f"{what}: {name!r} has unknown key(s) {', '.join(map(repr, extra))};"
                             f" give {{{keys[0]!r}: .., {keys[1]!r}: ..}}")
        return value.get(keys[0]), value.get(keys[1])
    if isinstance(value, (tuple, list)) and len(value) == 2:
        return value[0], value[1]
    raise InputError(f"{what}: {name!r} must be ({keys[0]}, {keys[1]}) or "
                     f"{{{keys[0]!r}: .., {keys[1]!r}: ..}}, not {value!r}")


def _number(what: str, name: str, key: str, x, allow_none: bool = False):
    if x is None and allow_none:
        return None
    try:
        v = float(x)
    except (TypeError, ValueError):
        v = float("nan")
    if not math.isfinite(v):
        raise InputError(f"{what}: {name!r} has {key} {x!r}; give a finite number"
                         + (" (or null for an open side)" if allow_none else ""))
    return v


def _read_json(path: Path, what: str):
    try:
        return json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise InputError(f"{what}: no file {str(path)!r}; give the path of a JSON file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise InputError(f"{what}: {str(path)!r} is not a readable JSON file ({e}); see "
                         "docs/guide/prior-and-bounds.md for the format") from None


def prior_from(source, scale: float = 1.0) -> dict[str, tuple[float, float]]:
    """A prior `{name: (mean, std)}` for [`fwid.fit`][]`(prior=...)` from an earlier result.

    **Arguments:**
    - `source`: a [`fwid.FitResult`][] (its estimates and their `std`), an identification
      (`fwid.identify`'s result: its one fit's, or with per-flight fits the mean over the
      flights and their spread, as `report.json`), a `report.json` dict (the report format: its top-level `"parameters"` `{name: {"value", "std"}}`), a prior dict
      (`{name: (mean, std)}` or `{name: {"mean": .., "std": ..}}`), or the path of a JSON
      file holding a report or a prior dict. Parameters without a finite positive std (one
      that sat at an active bound, a single flight's spread) and per-flight terms (`bq@0`)
      are left out: the prior says nothing about them.
    - `scale`: multiplies every std (e.g. 2 to trust the earlier result half as much).

    **Returns:** `{name: (mean, std)}`.
    """
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise InputError(f"prior_from: scale must be a positive number, not {scale!r}")
    if isinstance(source, (str, Path)):
        source = _read_json(Path(source), "prior")
    if hasattr(source, "fits") and hasattr(source, "flights"):  # an identification
        fits = list(source.fits)
        if len(fits) == 1:
            source = fits[0]
        else:
            names = [k for k in fits[0].names if "@" not in k]
            vals = np.array([[float(f.theta[f.names.index(k)]) for k in names] for f in fits])
            source = {k: (vals[:, i].mean(), vals[:, i].std(ddof=1))
                      for i, k in enumerate(names)}
    if hasattr(source, "theta") and hasattr(source, "names"):  # a FitResult
        source = {k: (float(m), float(s)) for k, m, s in
                  zip(source.names, np.asarray(source.theta), np.asarray(source.std))}
    if not isinstance(source, Mapping):
        raise InputError(f"prior: cannot build a prior from a {type(source).__name__}; give "
                         "{name: (mean, std)}, a FitResult, an identification or a report.json")
    if "parameters" in source and isinstance(source["parameters"], Mapping):  # a report
        source = {k: (v.get("value"), v.get("std")) for k, v in source["parameters"].items()}
    out = {}
    for k, v in source.items():
        if "@" in k:
            continue
        mean, std = _pair("prior", k, v, ("mean", "std"))
        if std is None or not (isinstance(std, (int, float, np.floating))
                               and math.isfinite(std) and std > 0):
            continue
        out[k] = (_number("prior", k, "mean", mean), float(std) * scale)
    return out


def _normalised_prior(prior) -> dict[str, tuple[float, float]]:
    """A prior as given to `fit` checked: every entry a finite mean and a positive std."""
    if prior is None:
        return {}
    if isinstance(prior, (str, Path)):
        prior = _read_json(Path(prior), "prior")
    if not isinstance(prior, Mapping) or "parameters" in prior:
        return prior_from(prior)  # a FitResult, an identification or a report
    out = {}
    for k, v in prior.items():
        mean, std = _pair("prior", k, v, ("mean", "std"))
        mean = _number("prior", k, "mean", mean)
        std = _number("prior", k, "std", std)
        if std <= 0:
            raise InputError(f"prior: {k!r} has std {std!r}; give a positive standard deviation")
        out[k] = (mean, std)
    return out


def bounds_from(bounds) -> dict[str, tuple[float | None, float | None]]:
    """Bounds `{name: (low, high)}` (or `{name: {"low": .., "high": ..}}`, or the path of a
    JSON file holding that; `None` or a missing key an open side) checked: finite numbers
    with `low < high`."""
    if bounds is None:
        return {}
    if isinstance(bounds, (str, Path)):
        bounds = _read_json(Path(bounds), "bounds")
    if not isinstance(bounds, Mapping):
        raise InputError(f"bounds: give {{name: (low, high)}}, not a {type(bounds).__name__}")
    out = {}
    for k, v in bounds.items():
        low, high = _pair("bounds", k, v, ("low", "high"))
        low = _number("bounds", k, "low", low, allow_none=True)
        high = _number("bounds", k, "high", high, allow_none=True)
        if low is not None and high is not None and not low < high:
            raise InputError(f"bounds: {k!r} has low {low:g} >= high {high:g}; give low < high "
                             "(null for an open side)")
        out[k] = (low, high)
    return out


def _entries(what: str, given: Mapping, model_name: str, free: Sequence[str],
             names: Sequence[str]) -> dict[str, list[int]]:
    """Which entries of the free vector (`names`) each given name sets: itself, or every
    flight's copy `k@i` of a per-flight parameter `k`; a name `k@i` sets flight `i`'s copy
    only (none where the fit has no per-flight copies). Unknown names: one-line InputError."""
    out = {}
    for k in given:
        idx = [i for i, n in enumerate(names) if n == k or n.split("@")[0] == k]
        if not idx and "@" in k and k.split("@")[0] in free:
            continue
        if not idx:
            raise InputError(f"{what}: {k!r} is not a free parameter of the {model_name} model; "
                             f"its free parameters are {', '.join(free)}")
        out[k] = idx
    return out


def prior_bounds(model, names: Sequence[str], prior=None, bounds=None) -> PriorBounds:
    """[`PriorBounds`][] over the free vector `names` (`FitResult.names`' layout) of `model`
    from a prior (anything [`prior_from`][] takes) and bounds ([`bounds_from`][])."""
    prior, bounds = _normalised_prior(prior), bounds_from(bounds)
    pb = PriorBounds.none(len(names))
    mean, weight = np.array(pb.mean), np.array(pb.weight)
    lower, upper = np.array(pb.lower), np.array(pb.upper)
    for k, idx in _entries("prior", prior, model.name, model.free, names).items():
        mean[idx], weight[idx] = prior[k][0], 1.0 / prior[k][1]
    for k, idx in _entries("bounds", bounds, model.name, model.free, names).items():
        low, high = bounds[k]
        lower[idx] = -np.inf if low is None else low
        upper[idx] = np.inf if high is None else high
    return PriorBounds(mean=jnp.asarray(mean), weight=jnp.asarray(weight),
                       lower=jnp.asarray(lower), upper=jnp.asarray(upper))


def prior_information(prior, names: Sequence[str]) -> np.ndarray:
    """The information matrix a prior adds, `diag(1 / std^2)` over `names` (0 where a name
    has no prior): to add to a Fisher information matrix (`M_total = M_data + this`).
    `prior`: anything [`fwid.prior_from`][] takes."""
    prior = _normalised_prior(prior)
    return np.diag([1.0 / prior[k][1] ** 2 if k in prior else 0.0 for k in names])


def has_any(pb: PriorBounds) -> bool:
    """Whether `pb` holds a prior or a bound at all."""
    return bool(np.any(np.asarray(pb.weight) > 0) or np.any(np.isfinite(np.asarray(pb.lower)))
                or np.any(np.isfinite(np.asarray(pb.upper))))
