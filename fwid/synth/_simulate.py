"""Simulate one DelFly flight: the paper's combined model (Sec. VI, Eqs. 13-15 with Eqs. 7-9)
plus realistic measurement: rippling control surfaces, sensor noise, and aerodynamic loads
reconstructed from the measured motion.

Independent numpy implementation (the "truth" fwid's estimator is tested against).

**Dynamics.** Nine perturbation states `x = [dq du dw dtheta dp dr dv dphi dpsi]` (Eq. 7,
Eqs. 8-9 side by side, always both axes, coupled only through an injected effect):

    x' = K x + G dF,   dF = Fx x + Fu u_eff  (Eqs. 1-6, cycle-averaged)
                          + gain(xc) F_TV(phi_f)  (Eq. 12, flapping)
                          + extra(xc, u_eff)     (injected effect, `_effects`)

integrated by superposition as `x = xc + xo`: `xc`, the cycle-averaged states, driven by the
(commanded) input and the effect terms; `xo`, the response to the flapping loads, started on
its periodic orbit (`periodic_state`). The model is linear, so this is the same as
integrating `x` (to rounding), and it lets the injected effects act on the cycle-averaged
states, as the effect catalogue describes them, without rectifying the flapping oscillation
into spurious trim shifts.

with `K` the gravity/trim-velocity/kinematic terms, `G` the inverse mass/inertia (with
`Ic = Ix Iz - Ixz^2` for roll/yaw) and `dpsi' = dr / cos(theta0)` (Eq. 9). The flapping
loads use the flapping phase `phi_f(t) = phase0 + integral of 2 pi f dt` (not `2 pi f t`:
the frequency varies), `F_TV = sum_n a_n sin(n phi_f) + b_n cos(n phi_f)`, n = 1..3.

**Integration.** Classical RK4 with a fixed step `dt / substeps` (`dt = 1 / rate`). The
control input is the sampled commanded (cycle-averaged) deflection, linearly interpolated
between samples (so `(u_k + u_k+1) / 2` at RK4 midpoints); the flapping loads are
evaluated at the exact stage times. With `flapping=False, ripple=False, noise=0,
effect="none"` (and `substeps=1`) a flight is therefore exactly fixed-step RK4 at the sample
step with linearly interpolated inputs, the scheme of fwid's estimator (paper Sec. IV.B).

**Measurement.** The CSV holds absolute values (trim + perturbation):

- states plus Gaussian white noise, `NOISE` per channel times the `noise` scale;
- `de`, `dr`: the commanded deflection plus a ripple locked to the flapping phase (first
  and second harmonic, amplitudes `RIPPLE` x the manoeuvre amplitude) plus noise. The EOM
  are driven by the commanded (cycle-averaged) deflection, not by the ripple (paper
  Sec. IV.A: "control surface deflections are also cycle-averaged");
- `f`: the true flapping frequency (12.5 Hz with a slow jitter of ~0.07 Hz rms, or with
  `drift=True` a ramp 11.5 -> 13.2 Hz over the flight) plus noise;
- `X Y Z L M N`: reconstructed from the measured (noisy) states as in the paper (Sec.
  III.A, "reconstructed from the states assuming rigid-body dynamics"), see
  `reconstruct_loads`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from ._delfly import ALL_PARAMS, DELFLY, FORCES, STATES, DelFly, aero_matrices, state_space
from ._effects import Effect
from ._inputs import DEFAULT_UNIT, N_UNITS, make_input
from ._reconstruct import LOAD_CUTOFF, reconstruct_loads

#: Columns of a flight CSV, in file order (the flight-data format).
COLUMNS = (
    "t", "q", "u", "w", "theta", "p", "r", "v", "phi", "psi",
    "de", "dr", "f", "X", "Y", "Z", "L", "M", "N",
)  # fmt: skip

#: Sensor noise standard deviations at `noise=1` (rad/s, m/s, rad, Hz). Roughly an optical
#: tracking system after the usual pre-processing (paper Sec. III.A).
NOISE = {
    "q": 0.02, "u": 0.005, "w": 0.005, "theta": 0.002,
    "p": 0.02, "r": 0.01, "v": 0.005, "phi": 0.002, "psi": 0.002,
    "de": 0.002, "dr": 0.002, "f": 0.02,
}  # fmt: skip

#: Control-surface ripple: `(fraction of the manoeuvre amplitude, phase [rad])` of the
#: first and second flapping harmonic, per surface.
RIPPLE = {"de": ((0.3, 0.4), (0.1, 1.1)), "dr": ((0.25, -0.7), (0.08, 0.3))}

#: Default manoeuvre amplitude [rad] per axis (elevator for `lon`, rudder for `lat`).
DEFAULT_AMPLITUDE = {"lon": 0.12, "lat": 0.25}

#: Flapping-frequency jitter: three slow sinusoids with these amplitude [Hz] and frequency
#: [Hz] ranges (random per flight).
JITTER_AMPLITUDE = (0.03, 0.07)
JITTER_FREQUENCY = (0.15, 1.2)

#: Frequency ramp [Hz] of `drift=True`, from the first to the last sample.
DRIFT = (11.5, 13.2)


_AXES = ("lon", "lat")


# ----------------------------------------------------------------------------- flapping
@dataclasses.dataclass(frozen=True)
class FlapFrequency:
    """The true flapping frequency `f(t) = f_start + slope t + sum_i A_i sin(2 pi nu_i t +
    c_i)` and its phase `phase0 + 2 pi integral_0^t f`, both analytic (so RK4 stages get the
    exact phase and a drifting frequency keeps the phase continuous)."""

    f_start: float
    slope: float = 0.0
    amps: tuple = ()
    freqs: tuple = ()
    phases: tuple = ()
    phase0: float = 0.0

    def f(self, t):
        t = np.asarray(t, dtype=float)
        out = self.f_start + self.slope * t
        for a, nu, c in zip(self.amps, self.freqs, self.phases):
            out = out + a * np.sin(2 * np.pi * nu * t + c)
        return out

    def phase(self, t):
        t = np.asarray(t, dtype=float)
        cyc = self.f_start * t + 0.5 * self.slope * t * t
        for a, nu, c in zip(self.amps, self.freqs, self.phases):
            cyc = cyc + a / (2 * np.pi * nu) * (np.cos(c) - np.cos(2 * np.pi * nu * t + c))
        return self.phase0 + 2 * np.pi * cyc


def flapping_loads(phase, vehicle: DelFly = DELFLY) -> np.ndarray:
    """Eq. 12 for all six loads: `(..., 6)` array `[X Y Z L M N]_TV` at flapping phase
    `phase` (h = 3 harmonics, `a` sine, `b` cosine)."""
    phase = np.asarray(phase, dtype=float)
    out = np.zeros(phase.shape + (6,))
    for i, F in enumerate(FORCES):
        c = vehicle.fourier(F)
        for n in range(3):
            out[..., i] += c[n, 0] * np.sin((n + 1) * phase) + c[n, 1] * np.cos((n + 1) * phase)
    return out


def periodic_state(vehicle: DelFly, frequency: float, phase: float = 0.0) -> np.ndarray:
    """The periodic (steady) response of the linear model (Eqs. 7-9) to the flapping loads
    (Eq. 12) at a constant `frequency`, evaluated where the flapping phase is `phase`:
    `Re sum_n (j n w I - A)^-1 G (b_n - j a_n) e^(j n phase)`, `w = 2 pi frequency`.
    Starting there, a flight with flapping begins in its flapping cycle, cycle-averaged at
    trim, with no start-up transient (exactly so for a constant frequency)."""
    A, _, G = state_space(vehicle)
    w = 2 * np.pi * frequency
    x = np.zeros(9, dtype=complex)
    for n in range(3):
        c = np.array([vehicle.fourier(F)[n, 1] - 1j * vehicle.fourier(F)[n, 0] for F in FORCES])
        x += np.linalg.solve(1j * (n + 1) * w * np.eye(9) - A, G @ c) * np.exp(1j * (n + 1) * phase)
    return x.real


# ----------------------------------------------------------------------------- RK4
def flapping_harmonics(phase, vehicle: DelFly = DELFLY) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 12 per harmonic: `(H, Q)`, each `(..., 3, 6)`, `H[..., n-1, :] = a_n sin(n phase)
    + b_n cos(n phase)` (their sum over n is `flapping_loads`) and the quadrature
    `Q[..., n-1, :] = a_n cos(n phase) - b_n sin(n phase)` (so Eq. 12 at `phase + d` is
    `sum_n H_n cos(n d) + Q_n sin(n d)`)."""
    phase = np.asarray(phase, dtype=float)[..., None]
    c = np.stack([vehicle.fourier(F) for F in FORCES], axis=-1)  # (3, 2, 6)
    n = np.arange(1.0, 4.0)
    s, co = np.sin(n * phase)[..., None], np.cos(n * phase)[..., None]
    return s * c[:, 0] + co * c[:, 1], co * c[:, 0] - s * c[:, 1]


def _integrate(vehicle, active, t_int, u_int, F_int, F_mid, H_int, H_mid, xc0, xo0, flapping,
               E_int=None, E_mid=None):
    """Fixed-step RK4 over the internal grid `t_int` (step h) of the cycle-averaged states
    `xc` and, with `flapping`, the flapping response `xo` (superposition, exact for the
    linear model: `x = xc + xo`):

        xc' = A xc + B u_eff + G extra(xc, u_eff, aux)         (Eqs. 7-9, 1-6 + effect)
        xo' = A xo + G flap(xc, u_eff, F_TV(phi_f(t)))         (Eq. 12 loads in Eqs. 7-9)
        aux' = effect's auxiliary dynamics (actuator, lagged states), u_eff = act(u, aux)

    (`extra` includes the effect's `timed_loads`, given on the grid and at the step midpoints
    as `E_int`/`E_mid`, or `None`.)

    Effects act on the cycle-averaged states (`active`: the effect's forms, `_effects`).
    `u_int` (N+1, 2): commanded input on the grid (linear between samples, so midpoints are
    averages); `F_int`/`F_mid`: flapping loads on the grid and at the step midpoints, and
    `H_*` their harmonics `(H, Q)` where a form needs them (else `None`). Returns
    `(xc, xo, aux)` on the grid (`aux` is `None` without auxiliary states)."""
    A, B, G = state_space(vehicle)
    na = active.n_aux
    ext = active.has_extra
    flap = active.has_flap
    io = 9 if flapping else None
    ia = 18 if flapping else 9
    nz = ia + na

    def rhs(z, u_cmd, F, H, E):
        xc = z[:9]
        aux = z[ia:]
        u = active.actuator(u_cmd, aux) if na else u_cmd
        dxc = A @ xc + B @ u
        if ext:
            dxc = dxc + G @ active.extra_loads(xc, u, aux)
        if E is not None:
            dxc = dxc + G @ E
        parts = [dxc]
        if flapping:
            Fg = active.flapping(xc, u, F, *H) if flap else F
            parts.append(A @ z[io : io + 9] + G @ Fg)
        if na:
            parts.append(active.aux_rhs(xc, u_cmd, u, aux))
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    n = t_int.shape[0]
    Z = np.zeros((n, nz))
    z = np.zeros(nz)
    z[:9] = xc0
    if flapping:
        z[io : io + 9] = xo0
    if na:
        z[ia:] = active.aux0(xc0)
    Z[0] = z
    h = t_int[1] - t_int[0] if n > 1 else 0.0
    none2 = (None, None)
    for j in range(n - 1):
        um = 0.5 * (u_int[j] + u_int[j + 1])
        Hj = (H_int[0][j], H_int[1][j]) if H_int is not None else none2
        Hm = (H_mid[0][j], H_mid[1][j]) if H_mid is not None else none2
        Hk = (H_int[0][j + 1], H_int[1][j + 1]) if H_int is not None else none2
        Ej, Em, Ek = ((E_int[j], E_mid[j], E_int[j + 1]) if E_int is not None
                      else (None, None, None))
        k1 = rhs(z, u_int[j], F_int[j], Hj, Ej)
        k2 = rhs(z + 0.5 * h * k1, um, F_mid[j], Hm, Em)
        k3 = rhs(z + 0.5 * h * k2, um, F_mid[j], Hm, Em)
        k4 = rhs(z + h * k3, u_int[j + 1], F_int[j + 1], Hk, Ek)
        z = z + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        Z[j + 1] = z
    xc = Z[:, :9]
    xo = Z[:, io : io + 9] if flapping else np.zeros_like(xc)
    return xc, xo, (Z[:, ia:] if na else None)


# ----------------------------------------------------------------------------- flight
def _noise_sigmas(noise) -> dict[str, float]:
    if isinstance(noise, Mapping):
        unknown = set(noise) - set(NOISE)
        if unknown:
            raise ValueError(f"unknown noise channel(s) {sorted(unknown)}; known: {list(NOISE)}")
        return {k: float(noise.get(k, v)) for k, v in NOISE.items()}
    s = float(noise)
    if not np.isfinite(s) or s < 0:
        raise ValueError(f"noise must be a scale >= 0 or a dict of sigmas, got {noise!r}")
    return {k: s * v for k, v in NOISE.items()}


def simulate_flight(
    *,
    axis: str = "lon",
    seed: int = 0,
    duration: float = 4.5,
    rate: float = 200.0,
    input: str = "3211",
    amplitude: float | None = None,
    noise: float | Mapping[str, float] = 1.0,
    flapping: bool = True,
    ripple: bool = True,
    drift: bool = False,
    effect: str | tuple | Effect = "none",
    strength: float | tuple = 1.0,
    form: str | tuple | None = None,
    substeps: int = 1,
    start: float = 1.0,
    unit: float | None = None,
    initial: Mapping[str, float] | None = None,
    phase0: float = 0.0,
    vehicle: DelFly = DELFLY,
    load_cutoff: float | None = LOAD_CUTOFF,
    loads: str = "reconstructed",
) -> dict:
    """Simulate one flight of the DelFly (paper Sec. VI, Eqs. 13-15 in Eqs. 7-9).

    **Arguments:**
    - `axis`: `"lon"` (elevator manoeuvre) or `"lat"` (rudder manoeuvre). Both axes are
      always simulated and all columns written.
    - `seed`: seeds `numpy.random.default_rng` (flapping-frequency jitter, sensor noise).
    - `duration` [s], `rate` [Hz]: samples `t = 0, 1/rate, ..., duration`.
    - `input`: `"3211"`, `"211"`, `"doublet"` or `"pulse"` (see `make_input`); `start` [s] is
      the end of the quiet trim start, `unit` [s] the step length (default per input).
    - `amplitude` [rad]: manoeuvre amplitude (default `DEFAULT_AMPLITUDE[axis]`).
    - `noise`: scale of `NOISE` (0: noise-free), or a dict of per-channel sigmas.
    - `flapping`: add the flapping loads (Eq. 12). `ripple`: measured surfaces ripple.
    - `drift`: flapping frequency ramps `DRIFT` (11.5 -> 13.2 Hz) instead of 12.5 Hz.
    - `effect`, `strength`, `form`: an unmodelled effect (`_effects`, the effect names)
      in one of its forms (`None`: the default form), or two at once (`"a+b"` or a tuple,
      with a tuple of forms), or an `Effect`.
    - `substeps`: RK4 steps per sample (1: exactly the estimator's scheme).
    - `initial`: initial perturbation by state name, added to the trim (with `flapping`,
      to the periodic flapping response at t = 0, `periodic_state`, so that the flight starts
      cycle-averaged at trim instead of with a start-up transient).
    - `phase0`: flapping phase at t = 0.
    - `vehicle`: the true parameters (default `DELFLY`).
    - `load_cutoff`: low-pass cut-off of the reconstructed loads of a noisy flight [Hz].
    - `loads`: `"reconstructed"` (default: from the measured motion, `reconstruct_loads`)
      or `"true"` (the exact loads the EOM saw, e.g. for exact-recovery tests on force
      outputs; noise-free reconstruction differs from them near input steps and at the
      first/last few samples, where the state derivative has a kink or is one-sided).

    **Returns:** a dict with one numpy array per `COLUMNS` entry (absolute values, SI units,
    radians) and `"meta"`: `trim` (the true trim, sidecar form), `first_input` (index),
    `vehicle`, `truth` (parameters, effect, strength, options; JSON-ready), `states`
    (true perturbation states, `(n, 9)` in `STATES` order) = `states_cycle_averaged` +
    `states_flap` (the two integrated parts), `clean` (noise-free columns),
    `loads_true` / `loads_flap` (true absolute loads / their flapping part Eq. 12, dicts by
    load name), `loads_effect` (true loads minus the paper's model, Eqs. 1-6 + 12, at the
    true states and the measured input: the load the effect adds), `u_cmd` / `u_eff` /
    `u_meas` (commanded / acting / logged deflection perturbations `[de, dr]`; `clean` holds
    the logged surface columns, which trail the true ones under `time-offset`),
    `phase` (flapping phase at the samples), `flap` (the `FlapFrequency`).
    """
    if axis not in _AXES:
        raise ValueError(f"axis must be 'lon' or 'lat', got {axis!r}")
    substeps = int(substeps)
    if substeps < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps}")
    if rate <= 0 or duration <= 0:
        raise ValueError("rate and duration must be > 0")
    if loads not in ("reconstructed", "true"):
        raise ValueError(f"loads must be 'reconstructed' or 'true', got {loads!r}")
    eff = effect if isinstance(effect, Effect) else Effect(effect, strength, form)
    active = eff.bind(vehicle)
    sig = _noise_sigmas(noise)
    rng = np.random.default_rng(seed)

    n = round(duration * rate) + 1
    t = np.arange(n) / rate
    trim = vehicle.trim()

    # --- flapping frequency (random draws first, in a fixed order)
    amps = rng.uniform(*JITTER_AMPLITUDE, 3)
    freqs = rng.uniform(*JITTER_FREQUENCY, 3)
    cphase = rng.uniform(0.0, 2 * np.pi, 3)
    if drift:
        f_start, slope = DRIFT[0], (DRIFT[1] - DRIFT[0]) / t[-1]
    else:
        f_start, slope = vehicle.f0, 0.0
    flap = FlapFrequency(f_start, slope, tuple(amps), tuple(freqs), tuple(cphase), phase0)
    normals = rng.standard_normal((n, len(NOISE)))

    # --- commanded input (perturbation), sampled
    amp = DEFAULT_AMPLITUDE[axis] if amplitude is None else float(amplitude)
    unit_s = DEFAULT_UNIT[input] if unit is None else float(unit)
    cmd = make_input(input, t, start, unit_s, amp)
    u_cmd = np.zeros((n, 2))
    u_cmd[:, 0 if axis == "lon" else 1] = cmd

    # --- integrate on the internal grid
    xc0 = np.zeros(9)
    for k, v in (initial or {}).items():
        if k not in STATES:
            raise ValueError(f"unknown initial state {k!r}; known: {STATES}")
        xc0[STATES.index(k)] = float(v)
    xo0 = periodic_state(vehicle, float(flap.f(0.0)), phase0) if flapping else np.zeros(9)
    N = (n - 1) * substeps
    h = 1.0 / (rate * substeps)
    t_int = np.arange(N + 1) * h
    u_int = active.command(t_int, t, u_cmd)
    if u_int is None:
        u_int = np.stack([np.interp(t_int, t, u_cmd[:, i]) for i in range(2)], axis=1)
    H_int = H_mid = None
    if flapping:
        F_int = flapping_loads(flap.phase(t_int), vehicle)
        F_mid = flapping_loads(flap.phase(t_int[:-1] + 0.5 * h), vehicle)
        if active.harmonics:
            H_int = flapping_harmonics(flap.phase(t_int), vehicle)
            H_mid = flapping_harmonics(flap.phase(t_int[:-1] + 0.5 * h), vehicle)
    else:
        F_int, F_mid = np.zeros((N + 1, 6)), np.zeros((N, 6))
    gusts = active.gusts(t_int, seed)
    gust_loads = None
    if gusts is not None:  # unmeasured loads: through the flapping-response channel (linear)
        Fx_, _ = aero_matrices(vehicle)
        cols = [STATES.index(c) for c in ("u", "w", "v")]
        gl = gusts @ Fx_[:, cols].T
        F_int = F_int + gl
        F_mid = F_mid + 0.5 * (gl[1:] + gl[:-1])
        gust_loads = gl[::substeps]
    E_int = E_mid = None
    if active.has_timed:  # loads following time and the flapping frequency
        t_mid = t_int[:-1] + 0.5 * h
        E_int, E_mid = active.timed_loads(t_int, flap.f(t_int)), active.timed_loads(t_mid, flap.f(t_mid))
    xc, xo, aux = _integrate(vehicle, active, t_int, u_int, F_int, F_mid, H_int, H_mid, xc0,
                             xo0, flapping, E_int, E_mid)
    xc, xo = xc[::substeps], xo[::substeps]
    x = xc + xo
    u_act = active.command(t, t, u_cmd)
    u_act = u_cmd if u_act is None else u_act
    u_eff = active.actuator(u_act, aux[::substeps]) if aux is not None else u_act
    u_meas = active.measured(t, u_cmd)  # the commanded deflection as logged

    # --- true loads at the samples (what the EOM saw at each sample)
    phase = flap.phase(t)
    Fx, Fu = aero_matrices(vehicle)
    dF = x @ Fx.T + u_eff @ Fu.T
    F_tv = np.zeros((n, 6))
    F_nom = flapping_loads(phase, vehicle) if flapping else F_tv
    if flapping:
        H = flapping_harmonics(phase, vehicle) if active.harmonics else (None, None)
        F_tv = active.flapping(xc, u_eff, F_nom, *H) if active.has_flap else F_nom
    extra = active.extra_loads(xc, u_eff, aux[::substeps] if aux is not None else xc[:, :0])
    if active.has_timed:
        timed = active.timed_loads(t, flap.f(t))
        extra = timed if extra is None else extra + timed
    dF = dF + F_tv + (0.0 if extra is None else extra)
    if gust_loads is not None:
        dF = dF + gust_loads
    # what the paper's model misses at the true states and the measured input
    dF_effect = dF - (x @ Fx.T + u_meas @ Fu.T + F_nom)
    load0 = np.array([trim[k + "0"] for k in FORCES])
    loads_true = {k: load0[i] + dF[:, i] for i, k in enumerate(FORCES)}
    loads_flap = {k: F_tv[:, i] for i, k in enumerate(FORCES)}
    loads_effect = {k: dF_effect[:, i] for i, k in enumerate(FORCES)}

    # --- measurement
    clean = {"t": t}
    for i, s in enumerate(STATES):
        clean[s] = trim[s + "0"] + x[:, i]
    ref = abs(amp) if amp != 0 else DEFAULT_AMPLITUDE[axis]
    for j, surf in enumerate(("de", "dr")):
        d = trim[surf + "0"] + u_cmd[:, j]
        if ripple:
            for hk, (frac, ph) in enumerate(RIPPLE[surf]):
                d = d + frac * ref * np.sin((hk + 1) * phase + ph)
        clean[surf] = active.measured(t, d)
    clean["f"] = flap.f(t)
    nz = np.flatnonzero(np.abs(cmd) > 0)
    first = int(nz[0]) if nz.size else None
    trim["f0"] = float(np.mean(clean["f"][: max(1, first or round(0.2 * rate))]))
    meas = {}
    for i, c in enumerate(NOISE):
        meas[c] = clean[c] + sig[c] * normals[:, i] if sig[c] > 0 else clean[c].copy()
    noisy = any(sig[c] > 0 for c in STATES)
    if loads == "true":
        rec = {k: v.copy() for k, v in loads_true.items()}
    else:
        rec = reconstruct_loads(meas, rate, trim, vehicle, load_cutoff if noisy else None)
    clean.update(loads_true)

    cols = {"t": t}
    for c in COLUMNS[1:]:
        cols[c] = rec[c] if c in FORCES else meas[c]

    truth = {
        "parameters": vehicle.params(ALL_PARAMS),
        **eff.truth(),
        "axis": axis,
        "seed": int(seed),
        "input": {
            "type": input,
            "surface": "de" if axis == "lon" else "dr",
            "start": float(start),
            "unit": unit_s,
            "amplitude": amp,
            "n_units": N_UNITS[input],
        },
        "flapping": bool(flapping),
        "ripple": bool(ripple),
        "drift": bool(drift),
        "substeps": substeps,
        "rate": float(rate),
        "noise": sig,
        "loads": loads,
        "flapping_frequency": {
            "f_start": float(f_start),
            "slope": float(slope),
            "jitter_amplitudes": amps.tolist(),
            "jitter_frequencies": freqs.tolist(),
            "jitter_phases": cphase.tolist(),
            "phase0": float(phase0),
        },
        "vehicle": vehicle.vehicle(),
    }
    meta = {
        "axis": axis,
        "trim": trim,
        "first_input": first,
        "vehicle": vehicle.vehicle(),
        "truth": truth,
        "states": x,
        "states_cycle_averaged": xc,
        "states_flap": xo,
        "clean": clean,
        "loads_true": loads_true,
        "loads_flap": loads_flap,
        "loads_effect": loads_effect,
        "u_cmd": u_cmd,
        "u_eff": np.array(u_eff),
        "u_meas": u_meas,
        "phase": phase,
        "flap": flap,
    }
    cols["meta"] = meta
    return cols
