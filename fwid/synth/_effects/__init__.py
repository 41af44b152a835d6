"""Unmodelled effects the simulator can inject (the effect names), for gap diagnosis, each
in a family of forms.

`Effect(name, strength, form)`: `name` one of `EFFECTS` (the catalogue) or
`OUT_OF_CATALOGUE`; `form` one of `FORMS[name]` (`None`: the first, the default, which is the
effect's original form, so flights made without `form` are unchanged bit for bit);
`strength` 0 switches it off exactly (the flight is then bit-for-bit the one without it).

**Strength 1** is "as strong as the noise on its loads": during a default manoeuvre (4.5 s,
200 Hz, 3211 on the axis that shows the form, sensor noise x1), the RMS of the load the
effect adds beyond the paper's model (`loads_effect` of a flight: true loads minus the
linear model, Eqs. 1-6 + Eq. 12, at the true states and the measured input) is comparable
to the RMS that sensor noise puts on the reconstructed load, on the load it hits most.
`effect_noise_ratio` (`_strength.py`) measures that ratio; `benchmarks/README.md` lists
it for every form. Loads and modulations scale linearly with the strength, time scales of
actuators and sensors in proportion to it.

Forms (equations in each module's docstring; index 0 is the default; forms are only ever
appended, so a form's index, which splits the diagnosis benchmark's halves, never changes):

| effect | forms | module |
|---|---|---|
| `flap-coupling` | `amplitude`, `control`, `phase`, `shape`, `harmonic` | `_flapping.py` |
| `nonlinear-aero` | `quadratic`, `cubic`, `rate-damping`, `cross`, `saturation`, `one-sided` | `_aero.py` |
| `lon-lat-coupling` | `control`, `lat-to-lon`, `lon-to-lat`, `rates`, `gyroscopic` | `_coupling.py` |
| `actuator-dynamics` | `lag`, `delay`, `servo`, `rate-limit`, `asymmetric`, `lag-delay`, `saturation`, `backlash` | `_actuator.py` |
| `unsteady-aero` | `state-lag`, `incidence-lag`, `second-order`, `lift-lag`, `wagner` | `_aero.py` |
| `time-offset` | `trailing`, `clock-drift`, `sample-hold`, `wandering`, `resync` (the control columns are late) | `_actuator.py` |
| `flap-frequency` | `thrust`, `quadratic`, `lateral`, `lagged`, `saturating` | `_frequency.py` |
| `turbulence` (out) | `gusts` | `_gusts.py` |
| `cg-offset` (out) | `attitude` | `_outside.py` |
| `battery-sag` (out) | `linear` | `_outside.py` |

`sensor-offset` (the name of `time-offset` before it joined the catalogue) is accepted as an
alias.

**Two effects at once**: `name` a tuple/list or an `"a+b"` string of distinct effects,
`form` likewise (one form per effect, `None` entries for defaults), `strength` one number
for all or one per effect. Their hooks compose (`_form.Active`): loads add, flapping
modulations and deflection dynamics apply in turn.

All effects act on the cycle-averaged states (the flapping oscillation is not rectified
into a trim shift). The scaled coefficients go to each flight's sidecar under
`truth.effect_coefficients` (for two effects: a dict per effect).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from . import _actuator, _aero, _coupling, _flapping, _frequency, _gusts, _outside
from ._form import Active, Form

#: Effect names, spelled as reports and `--effect` spell them.
EFFECTS = ("none", "flap-coupling", "nonlinear-aero", "lon-lat-coupling", "actuator-dynamics",
           "unsteady-aero", "time-offset", "flap-frequency")
#: Effects the simulator can inject that are not in the catalogue (see the module docstring).
OUT_OF_CATALOGUE = ("turbulence", "cg-offset", "battery-sag")
#: Older names still accepted.
ALIASES = {"sensor-offset": "time-offset"}

_CLASSES: dict[str, tuple[type[Form], ...]] = {
    "flap-coupling": _flapping.FORMS,
    "nonlinear-aero": _aero.NONLINEAR,
    "lon-lat-coupling": _coupling.FORMS,
    "actuator-dynamics": _actuator.ACTUATOR,
    "unsteady-aero": _aero.UNSTEADY,
    "time-offset": _actuator.SENSOR,
    "flap-frequency": _frequency.FORMS,
    "turbulence": _gusts.TURBULENCE,
    "cg-offset": _outside.CG_OFFSET,
    "battery-sag": _outside.BATTERY_SAG,
}
#: Form names per effect; the first is the default.
FORMS: dict[str, tuple[str, ...]] = {"none": ("none",)} | {
    e: tuple(c.name for c in cs) for e, cs in _CLASSES.items()}
#: Coefficients at strength 1 per effect and form.
FORM_COEFFICIENTS: dict[str, dict[str, dict[str, float]]] = {
    e: {c.name: dict(c.COEFFICIENTS) for c in cs} for e, cs in _CLASSES.items()}
#: Coefficients at strength 1 of each effect's default form (SI units).
COEFFICIENTS: dict[str, dict[str, float]] = {"none": {}} | {
    e: dict(cs[0].COEFFICIENTS) for e, cs in _CLASSES.items()}
#: Public alias of `COEFFICIENTS` (re-exported by `fwid.synth`).
EFFECT_COEFFICIENTS = COEFFICIENTS


def form_class(effect: str, form: str | None = None) -> type[Form]:
    """The class of `form` of `effect` (`None`: the default form)."""
    effect = ALIASES.get(effect, effect)
    if effect not in _CLASSES:
        raise ValueError(f"effect {effect!r} has no forms; choose one of {', '.join(_CLASSES)}")
    forms = FORMS[effect]
    if form is not None and form not in forms:
        raise ValueError(f"unknown form {form!r} of {effect}; choose one of {', '.join(forms)}")
    return _CLASSES[effect][forms.index(form) if form is not None else 0]


def form_axes(effect: str, form: str | None = None) -> tuple[str, ...]:
    """The manoeuvre axes (`lon`, `lat`) whose flights show `form` of `effect`."""
    return ("lon", "lat") if effect == "none" else form_class(effect, form).axes


def _split(x) -> tuple:
    if x is None:
        return (None,)
    if isinstance(x, str):
        return tuple(x.split("+"))
    return tuple(x)


@dataclasses.dataclass(frozen=True)
class Effect:
    """One unmodelled effect, or several at once, in a given form and strength (see the
    module docstring). After construction `name` and `form` are `"+"`-joined strings
    (`form` resolved to the form names), `strength` a float (or a tuple, one per effect)."""

    name: str = "none"
    strength: float = 1.0
    form: str | None = None

    def __post_init__(self):
        names = tuple(ALIASES.get(n, n) for n in _split(self.name))
        forms = _split(self.form)
        if len(forms) == 1 and len(names) > 1 and forms[0] is None:
            forms = (None,) * len(names)
        if len(forms) != len(names):
            raise ValueError(f"give one form per effect: {len(names)} effect(s), forms {self.form!r}")
        known = EFFECTS + OUT_OF_CATALOGUE
        for n in names:
            if n not in known:
                raise ValueError(f"unknown effect {n!r}; choose one of {', '.join(known)}")
        if len(names) > 1 and ("none" in names or len(set(names)) != len(names)):
            raise ValueError(f"effects combined must be distinct and not 'none', got {names}")
        s = self.strength
        strengths = tuple(float(v) for v in s) if isinstance(s, (tuple, list)) else (float(s),)
        if len(strengths) not in (1, len(names)):
            raise ValueError(f"give one strength, or one per effect, got {s!r}")
        for v in strengths:
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"effect strength must be a finite number >= 0, got {v}")
        resolved = tuple("none" if n == "none" else form_class(n, f).name
                         for n, f in zip(names, forms))
        object.__setattr__(self, "name", "+".join(names))
        object.__setattr__(self, "form", "+".join(resolved))
        object.__setattr__(self, "strength", strengths[0] if len(strengths) == 1 else strengths)

    @property
    def parts(self) -> tuple[tuple[str, str, float], ...]:
        """`(name, form, strength)` of each effect."""
        names, forms = self.name.split("+"), self.form.split("+")
        s = self.strength if isinstance(self.strength, tuple) else (self.strength,) * len(names)
        return tuple(zip(names, forms, s))

    @property
    def active(self) -> bool:
        return any(n != "none" and s != 0.0 for n, _, s in self.parts)

    def coefficients(self) -> dict:
        """The coefficients scaled by the strength (for two effects: a dict per effect)."""
        c = {n: (form_class(n, f).coefficients(s) if n != "none" else {})
             for n, f, s in self.parts}
        return c[self.name] if len(c) == 1 else c

    def bind(self, vehicle) -> Active:
        """The active forms, ready for the simulation of `vehicle`."""
        return Active([form_class(n, f)(s, vehicle) for n, f, s in self.parts
                       if n != "none" and s != 0.0])

    def lag_tau(self) -> float | None:
        """Time constant [s] of a first-order actuator lag (`actuator-dynamics`, `lag`)."""
        for n, f, s in self.parts:
            if (n, f) == ("actuator-dynamics", "lag") and s != 0.0:
                return _actuator.Lag.coefficients(s)["tau"]
        return None

    def truth(self) -> dict:
        """What the sidecar records about the effect."""
        s = self.strength
        return {
            "effect": self.name,
            "strength": list(s) if isinstance(s, tuple) else float(s),
            "form": self.form,
            "effect_coefficients": self.coefficients(),
        }
