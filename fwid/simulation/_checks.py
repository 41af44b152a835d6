"""Checks that an [`fwid.Experiment`][] is what it claims: a uniform time axis (the RK4
simulation of Sec. IV.B steps at `dt = t[1] - t[0]`), and arrays whose shapes match the model.

Concrete arrays only: under a JAX transformation (a tracer) the checks are skipped, since the
arrays were checked where they were made.
"""

from __future__ import annotations

from collections.abc import Sequence

import jax
import numpy as np
from jaxtyping import ArrayLike, Float

from .._errors import FlightDataError, InputError
from ..data._timebase import uniform_tolerance
from ..models._greybox import GreyBoxModel


def _concrete(a) -> bool:
    return not isinstance(a, jax.core.Tracer)


def check_time_axis(t: Float[ArrayLike, " n"], name: str = "Experiment") -> None:
    """`t` is 1-d, strictly increasing, with the uniform step `t[1] - t[0]` throughout.

    The simulation takes its step from the first two samples, so a gap or a longer step
    would be integrated as if it were one step: raises [`fwid.FlightDataError`][] naming the
    first bad index, the step found and the step expected, and the fix.
    """
    if not _concrete(t):
        return
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise InputError(f"{name}: t must be 1-d (one time per sample), got shape {t.shape}")
    if t.shape[0] < 2:
        raise InputError(f"{name}: t needs at least 2 samples, got {t.shape[0]}")
    d = np.diff(t)
    dt = float(d[0])
    if not (np.isfinite(t).all() and dt > 0):
        raise FlightDataError(f"{name}: t must be finite and increasing; t[0] = {t[0]:.6g}, "
                              f"t[1] = {t[1]:.6g}")
    tol = uniform_tolerance(t, dt)
    bad = np.flatnonzero(~(np.abs(d - dt) <= tol))
    if bad.size:
        j = int(bad[0])
        raise FlightDataError(
            f"{name}: the time axis is not uniform: at index {j + 1} (t = {t[j + 1]:.6g} s) "
            f"the step is {d[j]:.6g} s but {dt:.6g} s was expected (the step t[1] - t[0] the "
            f"simulation uses); {bad.size} step{'s' if bad.size > 1 else ''} differ. Split "
            f"the record into experiments at the gap (e.g. `fwid.Experiment(t[:{j + 1}], "
            f"u[:{j + 1}], z[:{j + 1}], ...)` and one from index {j + 1}), each on a uniform "
            "grid, and fit them together: `fwid.fit(model, [exp1, exp2])`"
        )


def check_lengths(t, u, z, name: str = "Experiment") -> None:
    """`u` and `z` have one row per time sample."""
    if not all(_concrete(a) for a in (t, u, z)) or np.ndim(t) != 1:
        return
    n = np.shape(t)[0]
    for label, a in (("u (inputs)", u), ("z (measured outputs)", z)):
        if np.ndim(a) != 2 or np.shape(a)[0] != n:
            raise InputError(
                f"{name}: {label} has shape {tuple(np.shape(a))} but t has {n} samples: "
                f"give {label.split()[0]} as an array of shape ({n}, channels)"
            )


def check_experiment(model: GreyBoxModel, exp, name: str = "Experiment") -> None:
    """The experiment's `t`, `u`, `z` and `x0` match `model`'s inputs, outputs and states;
    each mismatch is an [`fwid.InputError`][] that names the array and the model's channels."""
    check_time_axis(exp.t, name)
    check_lengths(exp.t, exp.u, exp.z, name)

    def names(ch: Sequence[str]) -> str:
        return ", ".join(ch) if ch else "none"

    nu, ny, nx = len(model.inputs), len(model.outputs), len(model.states)
    if exp.u.shape[-1] != nu:
        raise InputError(
            f"{name}: u has {exp.u.shape[-1]} column(s) but the {model.name} model has {nu} "
            f"input(s) ({names(model.inputs)}): give u of shape (n, {nu})")
    if exp.z.shape[-1] != ny:
        raise InputError(
            f"{name}: z has {exp.z.shape[-1]} column(s) but the {model.name} model has {ny} "
            f"output(s) ({names(model.outputs)}): give z of shape (n, {ny})")
    if getattr(exp, "x0_from_z", False) and not model.outputs_are_states:
        raise InputError(
            f"{name}: no x0 was given, and the {model.name} model's outputs "
            f"({names(model.outputs)}) are not its states ({names(model.states)}) and do not "
            "include them all, so the initial state cannot be taken from the first measured "
            "sample; pass it: "
            f"fwid.Experiment(t, u, z, x0=[{', '.join(model.states)}] at t[0])")
    if exp.x0.shape[-1:] != (nx,):
        raise InputError(
            f"{name}: x0 has shape {tuple(exp.x0.shape)} but the {model.name} model has {nx} "
            f"state(s) ({names(model.states)}): give x0 of shape ({nx},)")

