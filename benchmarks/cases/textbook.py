"""The textbook cases of `textbook_cases.py`: one description per case, fitted two ways.

A [`Case`][] holds a model written once for numpy and JAX (``xdot(x, u, p, c, xp)``,
``obs(x, u, p, c, xp)``), its parameter names and start values, and the records it is fitted
to. [`fit_fwid`][] fits it with fwid's public API and default settings, as a user would;
[`fit_reference`][] fits it with the independent numpy/scipy estimator of `peers/scipy_output_error.py`
(RK4, ``scipy.optimize.least_squares``, diagonal R relaxed between solves, as FVSysID's
``ml_oem`` and SIDPAC's ``oe``).

The data are read in place from ``../shared/flightdata`` (or ``$FWID_FLIGHTDATA_ROOT``), never
copied into the repository.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from peers.scipy_output_error import batch_of, fit_output_error


def data_root() -> Path:
    """The folder holding `jategaonkar_fvsysid2/` and `sidpac_v1_twin_otter/`."""
    env = os.environ.get("FWID_FLIGHTDATA_ROOT")
    if env:
        return Path(env)
    return (Path(__file__).resolve().parents[3] / "shared" / "flightdata").resolve()


@dataclass(frozen=True)
class Case:
    """One textbook case: the model, its parameters and how to load its records.

    ``records()`` returns a list of dicts with ``t`` (uniform, s), ``u`` (N, nu), ``z``
    (N, ny), ``x0`` (nx,) and ``consts`` (dict of floats the equations read).
    ``published``: the source's own estimates (name -> value) where there are any, and
    ``source`` where they come from.
    """

    key: str
    title: str
    names: tuple[str, ...]
    theta0: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    xdot: Callable
    obs: Callable
    records: Callable[[], list[dict]]
    files: tuple[str, ...]
    published: dict[str, float] = field(default_factory=dict)
    source: str = ""
    free: tuple[str, ...] | None = None  # the parameters estimated (default: all)

    def available(self) -> bool:
        return all((data_root() / f).exists() for f in self.files)


def fwid_model(case: Case):
    """The case as a `fwid.GreyBoxModel` (the equations evaluated with `jax.numpy`)."""
    import jax.numpy as jnp

    import fwid

    return fwid.GreyBoxModel(
        lambda x, u, p, c: case.xdot(x, u, p, c, jnp), states=case.states, inputs=case.inputs,
        h=lambda x, u, p, c: case.obs(x, u, p, c, jnp), outputs=case.outputs,
        params=dict(zip(case.names, map(float, case.theta0))), free=case.free, name=case.key)


def fit_fwid(case: Case, records=None, **kw):
    """`fwid.fit` with its defaults (``kw`` overrides them) on the case's records."""
    import fwid

    records = case.records() if records is None else records
    exps = [fwid.Experiment(r["t"], r["u"], r["z"], x0=r["x0"], consts=r["consts"])
            for r in records]
    return fwid.fit(fwid_model(case), exps, names=[r["name"] for r in records], **kw)


def fit_reference(case: Case, records=None, **kw):
    """The independent numpy/scipy output-error fit (diagonal R) from the case's start values.

    Returns `_baseline.fit_output_error`'s dict (``theta``, ``std``, ``R``, ...)."""
    records = case.records() if records is None else records
    batch = batch_of(case.xdot, case.obs, case.names, [r["t"] for r in records],
                     [r["u"] for r in records], [r["x0"] for r in records],
                     [r["consts"] for r in records])
    kw.setdefault("diag_R", True)
    return fit_output_error(None, case.theta0, None, None, [r["z"] for r in records], None,
                            batch=batch, **kw)


def as_table(names, theta, std) -> dict[str, dict[str, float]]:
    """``{name: {"value": .., "std": ..}}``."""
    return {k: {"value": float(v), "std": float(s)} for k, v, s in zip(names, theta, std)}


def fwid_table(case: Case, result) -> dict[str, dict[str, float]]:
    """A fwid `FitResult` as [`as_table`][] in the case's parameter order."""
    idx = [result.names.index(k) for k in case.names]
    return as_table(case.names, np.asarray(result.theta)[idx], np.asarray(result.std)[idx])


def agreement(case: Case, est: dict, ref: dict, rel_tol=0.005, std_tol=0.05) -> dict:
    """Per parameter: relative difference of ``est`` from ``ref`` and whether it passes.

    A parameter passes when within ``rel_tol`` of the reference, or, for a parameter whose
    reference is near zero (smaller than its own standard deviation, so that a relative
    difference means nothing), when within ``std_tol`` of the reference's standard
    deviation."""
    out = {}
    for k in case.names:
        v, r, s = est[k]["value"], ref[k]["value"], ref[k]["std"]
        rel = abs(v - r) / abs(r) if r != 0 else float("inf")
        near_zero = abs(r) < s
        ok = rel <= rel_tol or (near_zero and abs(v - r) <= std_tol * s)
        out[k] = {"rel": rel, "in_std": abs(v - r) / s, "near_zero": near_zero, "ok": ok}
    return out
