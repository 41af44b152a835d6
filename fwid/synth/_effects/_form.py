"""What a form of an unmodelled effect can do to a flight, and how active forms combine.

A form is one set of equations for one effect (`flap-coupling` as amplitude modulation,
as phase modulation, ...). It hooks into the simulation (`fwid.synth._simulate`) at these
points, every hook vectorised over leading axes (states `xc` `(..., 9)` in `STATES` order,
deflections `u` `(..., 2)` = `[dde, ddr]`, all cycle-averaged perturbations):

- `command(tq, t, u_cmd)`: the commanded deflection acting at times `tq` (a delay);
- `actuator(u, aux)` / `aux_rhs(xc, u_cmd, u, aux)` / `aux0(xc0)`: auxiliary states
  integrated with the flight (an actuator, a lagged state) and the deflection they let act;
- `extra_loads(xc, u, aux)`: cycle-averaged loads `[dX dY dZ dL dM dN]` added to Eqs. 1-6;
- `flapping(xc, u, F, H, Q)`: the flapping loads `F` (Eq. 12) as modulated by the motion,
  with `H[..., n, :] = a_n sin(n phi) + b_n cos(n phi)` and its quadrature
  `Q[..., n, :] = a_n cos(n phi) - b_n sin(n phi)` per harmonic when `harmonics` is set;
- `timed_loads(t, f)`: cycle-averaged loads `(len(t), 6)` that follow time and the true
  flapping frequency `f` rather than the states (thrust with the flapping frequency, a battery
  sagging over the flight);
- `measured(t, column)`: a measured control column as logged (a time offset between logs);
- `gusts(t, seed)`: unmeasured gust velocities `[ug, wg, vg]`.

Coefficients are given at strength 1 (`COEFFICIENTS`) and scaled by the strength; a form
is only instantiated for a strength > 0, so strength 0 is exactly the flight without it.
"""

from __future__ import annotations

import numpy as np


class Form:
    """One form of one effect at a given strength (see the module docstring).

    Class attributes: `effect`, `name`, `COEFFICIENTS` (at strength 1), `axes` (the
    manoeuvres, `lon` and/or `lat`, whose flights show it), `n_aux` (auxiliary states),
    `harmonics` (needs the per-harmonic flapping loads).
    """

    effect = ""
    name = ""
    COEFFICIENTS: dict[str, float] = {}
    axes = ("lon", "lat")
    n_aux = 0
    harmonics = False

    def __init__(self, strength: float, vehicle):
        self.strength = float(strength)
        self.vehicle = vehicle
        self.c = self.coefficients(strength)

    @classmethod
    def coefficients(cls, strength: float) -> dict[str, float]:
        """The coefficients at `strength` (linear in it unless a form says otherwise)."""
        return {k: float(v * strength) for k, v in cls.COEFFICIENTS.items()}

    # ------------------------------------------------------------------ hooks (no-ops)
    def command(self, tq, t, u_cmd):
        return None

    def aux0(self, xc0):
        return np.zeros(self.n_aux)

    def actuator(self, u, aux):
        return u

    def aux_rhs(self, xc, u_cmd, u, aux):
        return np.zeros(np.shape(aux))

    def extra_loads(self, xc, u, aux):
        return None

    def flapping(self, xc, u, F, H, Q):
        return F

    def timed_loads(self, t, f):
        return None

    def measured(self, t, column):
        return column

    def gusts(self, t, seed):
        return None


def _summed(parts):
    """The sum of the parts that are not `None`, or `None` if all are."""
    out = None
    for p in parts:
        if p is not None:
            out = p if out is None else out + p
    return out


def loads(shape, **by_load) -> np.ndarray:
    """A `(..., 6)` load array with the given loads (by name X Y Z L M N) filled in."""
    out = np.zeros(tuple(shape) + (6,))
    for k, v in by_load.items():
        out[..., "XYZLMN".index(k)] = v
    return out


class Active:
    """The active forms of a flight, composed: deflection hooks applied in turn, extra
    loads summed, flapping modulations applied in turn, auxiliary states side by side
    (`aux` is the concatenation of each form's, in order)."""

    def __init__(self, forms: list[Form]):
        self.forms = forms
        self.n_aux = sum(f.n_aux for f in forms)
        self.harmonics = any(f.harmonics for f in forms)
        self.has_extra = any(type(f).extra_loads is not Form.extra_loads for f in forms)
        self.has_flap = any(type(f).flapping is not Form.flapping for f in forms)
        self.has_timed = any(type(f).timed_loads is not Form.timed_loads for f in forms)
        bounds = np.cumsum([0] + [f.n_aux for f in forms])
        self._slices = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]

    def _aux(self, aux, i):
        return aux[..., self._slices[i]]

    def command(self, tq, t, u_cmd):
        """The commanded deflection `(len(tq), 2)` acting at `tq`, or `None` (as commanded)."""
        out = None
        for f in self.forms:
            got = f.command(tq, t, u_cmd)
            if got is not None:
                out = got
        return out

    def aux0(self, xc0):
        parts = [f.aux0(xc0) for f in self.forms if f.n_aux]
        return np.concatenate(parts) if parts else np.zeros(0)

    def actuator(self, u, aux):
        for i, f in enumerate(self.forms):
            u = f.actuator(u, self._aux(aux, i))
        return u

    def aux_rhs(self, xc, u_cmd, u, aux):
        parts = [f.aux_rhs(xc, u_cmd, u, self._aux(aux, i))
                 for i, f in enumerate(self.forms) if f.n_aux]
        return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=-1)

    def extra_loads(self, xc, u, aux):
        return _summed(f.extra_loads(xc, u, self._aux(aux, i)) for i, f in enumerate(self.forms))

    def timed_loads(self, t, f):
        """The summed `timed_loads` of the forms `(len(t), 6)`, or `None`."""
        return _summed(form.timed_loads(t, f) for form in self.forms)

    def flapping(self, xc, u, F, H, Q):
        for f in self.forms:
            F = f.flapping(xc, u, F, H, Q)
        return F

    def measured(self, t, column):
        for f in self.forms:
            column = f.measured(t, column)
        return column

    def gusts(self, t, seed):
        return _summed(f.gusts(t, seed) for f in self.forms)
