"""The three methods of `speed.py` on the problem of `_problem.py`, ready to time.

1. **fwid**: `fwid.fit` on one flight; for N flights, N *independent* fits in one batched
   call, `fwid.fit_each`. Where fwid has no `fit_each` (older versions), or the flights start
   from different values (`--start least-squares`), fwid's internal pure estimator
   `fwid.estimate._output_error._fit_batch` is vmapped over a leading flight axis instead
   (each flight a batch of one, fwid.fit's default settings read from its signature).
2. **scipy**: `_baseline.py` (numpy RK4 + `scipy.optimize.least_squares`, finite
   differences), one flight per call.
3. **JAX reference**: `_jax_reference.py` (`lax.scan` RK4, jacfwd, hand-written
   Gauss-Newton with step halving, R relaxed every iteration), `vmap` for batches.
"""

from __future__ import annotations

import inspect

import jax
import jax.numpy as jnp
import numpy as np

import fwid
from fwid.estimate import _each
from fwid.estimate import _output_error as _oe
from fwid.simulation import stack_experiments

from _baseline import fit_output_error
from _jax_reference import make_fit
from _measure import block, xla_memory
from _problem import AERO, DT, NAMES, experiment, lon_f_jax, make_lon_f_numpy

# fwid's internal estimator changed signature while this benchmark was written; follow both.
_FIT_BATCH_TAKES_SCALE = "scale" in inspect.signature(_oe._fit_batch).parameters
# the reference's settings (make_fit's defaults), recorded with the results
REFERENCE_SETTINGS = dict(max_iter=50, max_halvings=10, cost_rtol=1e-10, step_tol=1e-9)


class Bench:
    """The three methods on `flights` (from `_problem.make_flights`), each flight started from
    its row of `starts` (n, 16)."""

    def __init__(self, flights, starts):
        self.F = flights
        self.starts = starts  # (n, 16)
        self.model = fwid.longitudinal()
        assert tuple(self.model.free) == NAMES, self.model.free
        self.exps = [experiment(flights, i) for i in range(len(starts))]
        self.fwid_alone = {}  # flight -> (theta, std_cr, info) from fwid.fit on that flight alone
        sig = inspect.signature(fwid.fit).parameters
        self.fit_defaults = dict(
            diagonal=(sig["noise"].default == "diagonal"),
            max_passes=sig["max_passes"].default, max_steps=sig["max_steps"].default,
            rtol=sig["rtol"].default, cost_rtol=sig["cost_rtol"].default,
        )
        self._fwid_batched = None
        self._start_models = {}
        self.ref = make_fit(lon_f_jax, **REFERENCE_SETTINGS)  # (fit_one, fit_many)

    # -- fwid.fit, one flight per call -----------------------------------------------------
    def _start_model(self, i):
        # built once per flight, as the reference's start arrays are
        if i not in self._start_models:
            self._start_models[i] = self.model.with_params(
                dict(zip(NAMES, map(float, self.starts[i]))))
        return self._start_models[i]

    def fwid_fit(self, i):
        r = fwid.fit(self.model, self.exps[i], start=self._start_model(i))
        theta, std = block((r.theta, r.std_cr))
        info = dict(passes=int(r.passes), steps=int(r.steps), converged=bool(r.converged))
        self.fwid_alone[i] = (theta, std, info)
        return theta

    def fwid_fit_xla_memory(self, i=0):
        """The XLA buffers of the program fwid.fit runs (its filter_jit, already compiled)."""
        try:
            sm, a = self.fit_batch_args(i)
            if hasattr(_oe, "_fit_one_jit"):  # fwid.fit's program for a single flight
                lowered = _oe._fit_one_jit.lower(sm, a[0], self.exps[i], n_local_batch=0,
                                                 **self.fit_defaults)
            else:
                lowered = _oe._fit_batch_jit.lower(sm, *a, n_local_batch=0, **self.fit_defaults)
            return xla_memory(lowered.lowered.compile())
        except Exception:
            return None

    # -- fwid, N independent fits in one vmapped call --------------------------------------
    def fwid_batched_fn(self):
        if self._fwid_batched is None:
            model, kw = self.model, self.fit_defaults
            if _FIT_BATCH_TAKES_SCALE:  # older fwid: _fit_batch(model, s0, scale, batch, ...)
                def one(theta0, batch):
                    scale = jnp.where(jnp.abs(theta0) > 0, jnp.abs(theta0), 1.0)
                    out = _oe._fit_batch(model, theta0 / scale, scale, batch, n_local_batch=0,
                                         **kw)
                    return {**out, "theta": out["s"] * scale}
            else:  # fwid now: _fit_batch(model, theta0, batch, ...), scaling inside
                def one(theta0, batch):
                    return _oe._fit_batch(model, theta0, batch, n_local_batch=0, **kw)

            self._fwid_batched = jax.jit(jax.vmap(one))
        return self._fwid_batched

    def fwid_batched_args(self, n):
        theta0 = jnp.asarray(self.starts[:n])
        batches = [stack_experiments([e]) for e in self.exps[:n]]  # as fwid.fit does
        batch = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *batches)
        return theta0, batch

    @property
    def use_fit_each(self):
        """`fwid.fit_each` takes one start for all flights: usable when the starts agree."""
        return hasattr(fwid, "fit_each") and bool(np.all(self.starts == self.starts[0]))

    @property
    def batched_label(self):
        return "fwid.fit_each" if self.use_fit_each else "fwid vmap(_fit_batch)"

    def fwid_batched(self, n):
        """A call that fits flights 0..n-1 independently in one batched fwid call and returns
        `(theta (n, p), cramer_rao_std (n, p), info)`."""
        if self.use_fit_each:
            exps, sm = self.exps[:n], self._start_model(0)

            def call():
                rs = fwid.fit_each(self.model, exps, start=sm)
                theta, std = block((jnp.stack([r.theta for r in rs]),
                                     jnp.stack([r.std_cr for r in rs])))
                return theta, std, dict(passes_max=max(int(r.passes) for r in rs),
                                        steps=[int(r.steps) for r in rs],
                                        all_converged=all(bool(r.converged) for r in rs))
        else:
            fb, a = self.fwid_batched_fn(), self.fwid_batched_args(n)

            def call():
                out = block(fb(*a))
                return (out["theta"], np.sqrt(np.diagonal(out["cov_cr"], axis1=-2, axis2=-1)),
                        dict(passes_max=int(out["passes"].max()), steps=out["steps"].tolist(),
                             all_converged=bool(out["converged"].all())))
        return call

    def fwid_batched_xla_memory(self, n):
        try:
            if self.use_fit_each:
                theta0s = jnp.stack([self._start_model(0).theta()] * n)
                nmax = max(e.n for e in self.exps[:n])
                stacked = jax.tree_util.tree_map(
                    lambda *a: jnp.stack(a), *[stack_experiments([e], n=nmax) for e in self.exps[:n]])
                lowered = _each._fit_each_batched.lower(self.model, theta0s, stacked,
                                                        n_local_batch=0, **self.fit_defaults)
                return xla_memory(lowered.lowered.compile())
            return xla_memory(self.fwid_batched_fn().lower(*self.fwid_batched_args(n)).compile())
        except Exception:
            return None

    def fit_batch_args(self, i=0):
        """The arguments fwid.fit gives `_fit_batch` for flight i alone (positional part)."""
        sm = self._start_model(i)
        theta0 = sm.theta()
        batch = stack_experiments([self.exps[i]])
        if _FIT_BATCH_TAKES_SCALE:
            scale = jnp.where(jnp.abs(theta0) > 0, jnp.abs(theta0), 1.0)
            return sm, (theta0 / scale, scale, batch)
        return sm, (theta0, batch)

    # -- JAX reference ---------------------------------------------------------------------
    def ref_args(self, n):
        F = self.F
        return (jnp.asarray(self.starts[:n]), jnp.asarray(F["u"][:n]), jnp.asarray(F["z"][:n]),
                jnp.asarray(F["x0"][:n]), jnp.full(n, DT),
                {k: jnp.asarray(v[:n]) for k, v in F["consts"].items()})

    def ref_args_one(self):
        """`ref_args(1)` without the flight axis: the arguments of the reference's `fit_one`."""
        return [x[0] if not isinstance(x, dict) else {k: v[0] for k, v in x.items()}
                for x in self.ref_args(1)]

    # -- scipy -----------------------------------------------------------------------------
    def scipy_fit(self, i, max_outer=50):
        F = self.F
        f = make_lon_f_numpy(F["consts_list"][i])
        return fit_output_error(f, self.starts[i], [F["t"]], [F["u"][i]], [F["z"][i]],
                                [F["x0"][i]], rtol=self.fit_defaults["cost_rtol"],
                                max_outer=max_outer)

    def settings(self):
        """The settings of the three methods, for the results' JSON."""
        return dict(
            fwid_fit_settings=self.fit_defaults,
            scipy_settings=dict(rtol=self.fit_defaults["cost_rtol"], method="trf",
                                jac="2-point"),
            reference_settings=REFERENCE_SETTINGS,
        )


def agreement(theta, theta_fwid, std_fwid):
    """Largest relative difference of the 12 aero parameters, and in Cramer-Rao stds."""
    a = slice(0, len(AERO))
    d = np.abs(theta[..., a] - theta_fwid[..., a])
    return dict(max_rel_diff_aero=float(np.max(d / np.abs(theta_fwid[..., a]))),
                max_diff_in_std_aero=float(np.max(d / std_fwid[..., a])))

