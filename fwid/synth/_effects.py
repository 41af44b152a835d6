"""Unmodelled effects the simulator can inject (CONTRACTS section 4), for gap diagnosis.

Each effect has a `strength`: 0 switches it off exactly (the flight is then bit-for-bit the
one without the effect), 1 is sized so that "a careful analyst could see it": the effect
changes the states during a default manoeuvre by several times the sensor noise, yet the
paper's linear model plus Fourier series (Eqs. 7-8, 12) still fits the flight reasonably.
Effects scale linearly with `strength` (the actuator time constant too).

- `flap-coupling`: the flapping loads of Eq. 12 are multiplied by a gain that follows the
  body motion, `1 + s (kw dw + kq dq + kv dv + kp dp)`, breaking time-scale separation. The
  gain uses the cycle-averaged perturbation states (the simulator integrates those apart
  from the flapping response, see `_simulate.py`).
- `nonlinear-aero`: extra cycle-averaged loads, quadratic in the states:
  `dX += s cx du^2`, `dZ += s cz dw|dw|`, `dM += s cm dw|dw|`, `dY += s cy dv|dv|`,
  `dN += s cn dv|dv|`.
- `lon-lat-coupling`: the elevator and pitch rate drive the lateral loads
  (`dY += s ye dde`, `dL += s (le dde + lq dq)`, `dN += s (ne dde + nq dq)`) and the rudder
  drives the pitching moment (`dM += s md ddr`). A longitudinal flight then shows a lateral
  response (all columns are always simulated and written).
- `actuator-dynamics`: the deflection that acts on the vehicle is the commanded
  (cycle-averaged) one through a first-order lag, `d_eff' = (d_cmd - d_eff) / tau` with
  `tau = s * 0.05 s`; the measured columns `de`, `dr` keep the commanded deflection.

Outside the catalogue, to check that the diagnosis does not name a catalogue effect for
something else (`OUT_OF_CATALOGUE`):

- `turbulence`: wind gusts `ug, wg, vg` (white noise through a first-order filter at
  `GUST_BANDWIDTH` Hz, RMS `s * GUST_RMS` m/s) act through the vehicle's own velocity
  derivatives, `dF = Fx [ug, wg, vg]`: unmeasured loads, no new physics.

All effects act on the cycle-averaged states (the flapping oscillation is not rectified
into a trim shift). The coefficients are module constants (`COEFFICIENTS`) and are written
to each flight's sidecar under `truth.effect_coefficients`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.signal import lfilter

#: Effect names (CONTRACTS section 4).
EFFECTS = ("none", "flap-coupling", "nonlinear-aero", "lon-lat-coupling", "actuator-dynamics")
#: Effects the simulator can inject that are not in the catalogue (see the module docstring).
OUT_OF_CATALOGUE = ("turbulence",)
#: Gust RMS [m/s] at strength 1 and the bandwidth [Hz] of the gust filter (`turbulence`).
GUST_RMS = 0.06
GUST_BANDWIDTH = 1.0

#: Coefficients of each effect at strength 1 (SI units; states are perturbations).
COEFFICIENTS: dict[str, dict[str, float]] = {
    "none": {},
    "flap-coupling": {"kw": 1.5, "kq": 0.1, "kv": 1.0, "kp": 0.02},
    "nonlinear-aero": {"cx": -0.15, "cz": -0.25, "cm": 6.0e-3, "cy": -0.08, "cn": -1.5e-3},
    "lon-lat-coupling": {
        "ye": -0.02,
        "le": 2.0e-5,
        "lq": 1.0e-6,
        "ne": -5.0e-4,
        "nq": 2.0e-5,
        "md": 2.0e-3,
    },
    "actuator-dynamics": {"tau": 0.05},
    "turbulence": {"gust_rms": GUST_RMS},
}
#: Public alias of `COEFFICIENTS` (re-exported by `fwid.synth`).
EFFECT_COEFFICIENTS = COEFFICIENTS


@dataclasses.dataclass(frozen=True)
class Effect:
    """One unmodelled effect at a given strength (see the module docstring)."""

    name: str = "none"
    strength: float = 1.0

    def __post_init__(self):
        if self.name not in EFFECTS + OUT_OF_CATALOGUE:
            raise ValueError(f"unknown effect {self.name!r}; choose one of "
                             f"{', '.join(EFFECTS + OUT_OF_CATALOGUE)}")
        if not np.isfinite(self.strength) or self.strength < 0:
            raise ValueError(f"effect strength must be a finite number >= 0, got {self.strength}")

    @property
    def active(self) -> bool:
        return self.name != "none" and self.strength != 0.0

    def coefficients(self) -> dict[str, float]:
        """The effect's coefficients scaled by `strength`."""
        return {k: float(v * self.strength) for k, v in COEFFICIENTS[self.name].items()}

    # `x` is (..., 9) in fwid.synth STATES order, `u` is (..., 2) = [dde, ddr].
    def flap_gain(self, x: np.ndarray):
        """Multiplier of the flapping loads (1 unless `flap-coupling`)."""
        if self.name != "flap-coupling" or not self.active:
            return 1.0
        c = self.coefficients()
        dq, dp, dw, dv = x[..., 0], x[..., 4], x[..., 2], x[..., 6]
        return 1.0 + c["kw"] * dw + c["kq"] * dq + c["kv"] * dv + c["kp"] * dp

    def extra_loads(self, x: np.ndarray, u: np.ndarray):
        """Extra cycle-averaged loads `[dX, dY, dZ, dL, dM, dN]` (shape `(..., 6)`), or
        `None` when the effect adds none."""
        if not self.active or self.name not in ("nonlinear-aero", "lon-lat-coupling"):
            return None
        c = self.coefficients()
        out = np.zeros(np.shape(x)[:-1] + (6,))
        if self.name == "nonlinear-aero":
            du, dw, dv = x[..., 1], x[..., 2], x[..., 6]
            out[..., 0] = c["cx"] * du * du
            out[..., 2] = c["cz"] * dw * np.abs(dw)
            out[..., 4] = c["cm"] * dw * np.abs(dw)
            out[..., 1] = c["cy"] * dv * np.abs(dv)
            out[..., 5] = c["cn"] * dv * np.abs(dv)
        else:
            de, dr, dq = u[..., 0], u[..., 1], x[..., 0]
            out[..., 1] = c["ye"] * de
            out[..., 3] = c["le"] * de + c["lq"] * dq
            out[..., 5] = c["ne"] * de + c["nq"] * dq
            out[..., 4] = c["md"] * dr
        return out

    def lag_tau(self) -> float | None:
        """Actuator time constant [s], or `None` when the deflection acts directly."""
        if self.name != "actuator-dynamics" or not self.active:
            return None
        return self.coefficients()["tau"]

    def gusts(self, t: np.ndarray, seed: int) -> np.ndarray | None:
        """Gust velocities `(n, 3)` = `[ug, wg, vg]` at times `t` (`turbulence`), else `None`.
        Drawn from their own generator, so the flight's other random draws do not change."""
        if self.name != "turbulence" or not self.active:
            return None
        rng = np.random.default_rng([seed, 7919])
        h = t[1] - t[0]
        a = np.exp(-2 * np.pi * GUST_BANDWIDTH * h)
        w = rng.standard_normal((len(t), 3)) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal(3)  # g_0: stationary from t = 0
        g = lfilter((1.0,), (1.0, -a), w, axis=0)  # first-order Gauss-Markov: g_k = a g_k-1 + w_k
        return g * self.coefficients()["gust_rms"]

    def truth(self) -> dict:
        """What the sidecar records about the effect."""
        return {
            "effect": self.name,
            "strength": float(self.strength),
            "effect_coefficients": self.coefficients(),
        }
