"""The identified model as a linear state-space system `x' = A x + B u`, `y = C x + D u`,
linearised at the trim (the perturbation models' `x = 0, u = 0`, Eqs. 7-9), with the names
of its states, inputs and outputs: a model that leaves fwid for scipy or python-control."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..models._greybox import GreyBoxModel


@dataclass(frozen=True)
class StateSpace:
    """A linear system with named states, inputs and outputs: `x' = A x + B u`, `y = C x + D u`.

    SI units (rad, rad/s, m/s), perturbations from the trim. Bias terms (constant offsets of
    the aerodynamic model, flight-specific) are not part of the linear system.

    **Fields:**

    - `A (nx, nx)`, `B (nx, nu)`, `C (ny, nx)`, `D (ny, nu)`: the matrices (numpy arrays).
    - `states`, `inputs`, `outputs`: their names, in the matrices' order.

    `to_scipy()`, `to_control()` and `to_json()` / `from_json()` carry it out of fwid;
    `poles()` gives the eigenvalues of `A`.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]

    def __repr__(self) -> str:
        return (f"StateSpace(states={list(self.states)}, inputs={list(self.inputs)}, "
                f"outputs={list(self.outputs)}, poles={np.round(self.poles(), 4).tolist()})")

    def poles(self) -> np.ndarray:
        """The eigenvalues of `A`."""
        return np.linalg.eigvals(self.A)

    def to_scipy(self):
        """A `scipy.signal.StateSpace` (continuous time)."""
        from scipy import signal

        return signal.StateSpace(self.A, self.B, self.C, self.D)

    def to_control(self):
        """A `control.StateSpace` (python-control) with the state, input and output names."""
        try:
            import control
        except ImportError:
            raise ImportError("to_control needs python-control: pip install control "
                              "(or pip install 'fwid[control]'); to_scipy() needs nothing more"
                              ) from None
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states),
                          inputs=list(self.inputs), outputs=list(self.outputs))

    @classmethod
    def from_json(cls, d: dict) -> "StateSpace":
        """The system `to_json` wrote (e.g. `report.json["state_space"]` of `fwid identify`),
        without fitting again."""
        return cls(*(np.asarray(d[k], dtype=float) for k in "ABCD"),
                   *(tuple(d[k]) for k in ("states", "inputs", "outputs")))

    def to_json(self) -> dict:
        return {"A": self.A.tolist(), "B": self.B.tolist(), "C": self.C.tolist(),
                "D": self.D.tolist(), "states": list(self.states), "inputs": list(self.inputs),
                "outputs": list(self.outputs),
                "note": "x' = A x + B u, y = C x + D u: perturbations from the trim, SI units "
                        "(rad, rad/s, m/s); bias terms left out"}


def state_space(model: GreyBoxModel, consts: Mapping[str, float], params=None) -> StateSpace:
    """Linearise `model` at the trim: `A = df/dx`, `B = df/du`, `C = dh/dx`, `D = dh/du`.

    `f` is the model's state equation and `h` its output equation, taken at `x = 0, u = 0`
    as [`fwid.eigenvalues`][] does.

    **Arguments:**

    - `model`: a [`fwid.GreyBoxModel`][].
    - `consts`: its constants (vehicle and trim), e.g. `Identification.consts`.
    - `params`: parameter values overriding the model's (default: the model's).

    **Returns:** a [`fwid.StateSpace`][].
    """
    p = model.params if params is None else {**model.params, **params}
    A, B = model.state_matrices(p, consts)  # both convert to float arrays (as_arrays)
    C, D = model.output_matrices(p, consts)
    return StateSpace(*(np.asarray(M, dtype=float).reshape(shape) for M, shape in (
        (A, (len(model.states), len(model.states))), (B, (len(model.states), len(model.inputs))),
        (C, (len(model.outputs), len(model.states))),
        (D, (len(model.outputs), len(model.inputs))))),
        states=tuple(model.states), inputs=tuple(model.inputs), outputs=tuple(model.outputs))
