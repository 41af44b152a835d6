"""Raw recordings of a simulated flight, as a lab records them: an optical tracking take (pose
noise, dropouts, the tracking system's rate) and the autopilot's log (controls, flapping
frequency, gyro with bias and noise, on its own clock at its own rate).

The flight itself is the full nonlinear 6-DOF one (`_sixdof.py`) driven by the same inputs,
flapping frequency and aerodynamic loads as the linear simulator's flight (`simulate_flight`,
run noise-free on the take's time base for them). An injected effect (`effect`) enters as
the loads the linear flight's effect added (`loads_effect`), taken along the linear
flight's time history (open loop: exact for effects that do not depend on the states, close
for the small motions of the default inputs otherwise).

Clocks: the tracking clock is the simulation's (`t = 0` at the first frame of the take); the
autopilot's clock is `t_onboard = t_tracking - clock_offset_s` (the raw-recording formats). The log
starts `lead` seconds after the take and ends `tail` seconds after it, so both sources
overlap over all but the take's first `lead` seconds.
"""

from __future__ import annotations

import numpy as np

from ._delfly import DELFLY, DelFly
from ._simulate import NOISE, RIPPLE, simulate_flight
from ._sixdof import START_POSITION, initial_state, integrate, sixdof_model

#: Default manoeuvre amplitude [rad] of raw flights: small enough that the 6-DOF flight
#: stays within a few per cent of the linear one (the rudder's is below `DEFAULT_AMPLITUDE`'s
#: 0.25 rad, which rolls the vehicle by ~85 degrees).
RAW_AMPLITUDE = {"lon": 0.12, "lat": 0.1}

#: Tracking defaults: `position` noise [m] and `attitude` noise [deg] (1 sigma per axis,
#: typical of an optical system), `dropouts` (share of frames lost), `gap` (frames per
#: dropout, min and max), `rate` [Hz].
TRACKING = {"position": 4e-4, "attitude": 0.15, "dropouts": 0.005, "gap": (2, 8), "rate": 200.0}

#: Autopilot-log defaults: `rate` [Hz], gyro `bias` (uniform +- per axis) and white `noise`
#: [rad/s], `clock` (the clock offset is drawn uniform in +- this [s] unless given), the log's
#: `lead` and `tail` [s] (uniform ranges) relative to the take.
ONBOARD = {"rate": 512.0, "bias": 0.03, "noise": 0.005, "clock": 200.0,
           "lead": (0.05, 0.25), "tail": (0.1, 0.5)}


def _dropouts(rng, n: int, share: float, gap: tuple[int, int], margin: int = 10) -> np.ndarray:
    """A boolean mask of `n` frames, True where tracking lost the body: gaps of `gap[0]` to
    `gap[1]` frames, `round(share n)` frames in all, never in the first and last `margin`."""
    lost = np.zeros(n, dtype=bool)
    target = int(round(share * n))
    room = n - 2 * margin
    if target <= 0 or room <= 0:
        return lost
    target = min(target, room // 2)
    lengths = []
    while sum(lengths) < target:
        lengths.append(int(min(rng.integers(gap[0], gap[1] + 1), target - sum(lengths))))
    # place the gaps in order with at least one tracked frame between them
    free = room - sum(lengths) - (len(lengths) - 1)
    cuts = np.sort(rng.integers(0, free + 1, len(lengths)))
    start = margin
    prev = 0
    for c, k in zip(cuts, lengths):
        start += int(c - prev)
        lost[start : start + k] = True
        start += k + 1
        prev = c
    return lost


def intervals(t, lost) -> list[list[float]]:
    """The dropouts `[[t_first_lost, t_last_lost], ...]` of a lost-frame mask."""
    idx = np.flatnonzero(np.diff(np.concatenate([[0], lost.astype(int), [0]])))
    return [[float(t[a]), float(t[b - 1])] for a, b in zip(idx[::2], idx[1::2])]


def _small_rotations(rng, n: int, sigma: float) -> np.ndarray:
    """Quaternions `(n, 4)` of rotation vectors drawn N(0, sigma^2) per axis [rad]."""
    rv = sigma * rng.standard_normal((n, 3))
    ang = np.linalg.norm(rv, axis=1)
    half = 0.5 * ang
    k = np.where(ang > 0, np.sin(half) / np.where(ang > 0, ang, 1.0), 0.5)
    return np.column_stack([np.cos(half), k[:, None] * rv])


def quat_mul(a, b) -> np.ndarray:
    """Hamilton product of quaternions `(..., 4)`, scalar first (numpy)."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, float), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, float), -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], -1)


def _ripple(phase, amp) -> dict[str, np.ndarray]:
    ref = abs(amp)
    return {s: sum(frac * ref * np.sin((k + 1) * phase + ph) for k, (frac, ph) in enumerate(RIPPLE[s]))
            for s in ("de", "dr")}


def simulate_raw(
    *,
    axis: str = "lon",
    seed: int = 0,
    duration: float = 4.5,
    rate: float = TRACKING["rate"],
    position_noise: float = TRACKING["position"],
    attitude_noise: float = TRACKING["attitude"],
    dropouts: float = TRACKING["dropouts"],
    onboard_rate: float = ONBOARD["rate"],
    clock_offset: float | None = None,
    amplitude: float | None = None,
    onboard: bool = True,
    vehicle: DelFly = DELFLY,
    **flight_kw,
) -> dict:
    """Simulate one flight with the 6-DOF model and record it as a lab would.

    **Arguments:**
    - `axis`, `seed`, `duration` [s]: as `simulate_flight` (the take lasts `duration`).
    - `rate` [Hz]: the tracking system's frame rate (the take's and the truth's time base).
    - `position_noise` [m], `attitude_noise` [deg]: pose noise, 1 sigma per axis (the
      attitude's as a small body-axis rotation).
    - `dropouts`: share of frames where tracking lost the body (gaps of a few frames).
    - `onboard_rate` [Hz]: the autopilot log's rate.
    - `clock_offset` [s]: `t_tracking - t_onboard`; `None` draws it uniform in +-200 s.
    - `amplitude` [rad]: manoeuvre amplitude (default `RAW_AMPLITUDE[axis]`).
    - `onboard`: also record the autopilot's log (`False`: `onboard` is `None`).
    - `vehicle`, `flight_kw`: passed to `simulate_flight` (`input`, `start`, `effect`,
      `strength`, `form`, `drift`, ...).

    **Returns:** a dict: `truth` (a flight file's columns on the take's time base, noise-free,
    loads exact, plus the pose `x y z qw qx qy qz`), `take` (`t`, `position` (n, 3) NED [m]
    and `quat` (n, 4) body -> NED with NaN rows where lost, `de dr f` measured), `onboard`
    (`t` on the autopilot clock, `de dr f p q r`), `lost` (mask), `meta` (`clock_offset_s`,
    `gyro_bias`, `dropouts` intervals, `trim`, `first_input`, `truth`, options).
    """
    rng = np.random.default_rng(seed)
    sim_seed = int(rng.integers(2**31 - 1))
    lead = float(rng.uniform(*ONBOARD["lead"]))
    tail = float(rng.uniform(*ONBOARD["tail"]))
    drawn_offset = float(rng.uniform(-ONBOARD["clock"], ONBOARD["clock"]))
    offset = drawn_offset if clock_offset is None else float(clock_offset)
    bias = rng.uniform(-ONBOARD["bias"], ONBOARD["bias"], 3)
    if rate <= 0 or onboard_rate <= 0 or duration <= 0:
        raise ValueError("rate, onboard_rate and duration must be > 0")
    if not 0 <= dropouts < 0.5:
        raise ValueError(f"dropouts must be a share in [0, 0.5), got {dropouts}")
    amp = RAW_AMPLITUDE[axis] if amplitude is None else float(amplitude)

    n_take = round(duration * rate) + 1
    n_sim = n_take + int(np.ceil(tail * rate))
    sim_duration = (n_sim - 1) / rate
    fl = simulate_flight(axis=axis, seed=sim_seed, duration=sim_duration, rate=rate, noise=0.0,
                         amplitude=amp, loads="true", vehicle=vehicle, **flight_kw)
    meta = fl["meta"]
    t_sim = fl["t"]
    eff = meta["truth"].get("effect", "none")
    e_in = None if eff in ("none", None) else np.column_stack(list(meta["loads_effect"].values()))
    model = sixdof_model(meta["flap"], t_sim, meta["u_meas"], e_in, vehicle)

    # the autopilot's samples: its clock runs from `lead - offset`, in tracking time `s`
    n_ob = int(np.floor((sim_duration - lead) * onboard_rate)) + 1 if onboard else 0
    t_ob = (lead - offset) + np.arange(n_ob) / onboard_rate
    s_ob = np.minimum(t_ob + offset, sim_duration)
    t_take = t_sim[:n_take]
    ts = np.concatenate([t_take, s_ob])
    order = np.argsort(ts, kind="stable")
    step = (1.0 / rate) / int(np.ceil((1.0 / rate) / 1e-3))  # <= 1 ms, divides the sample step
    sol = integrate(model, initial_state(meta["states"][0], vehicle, START_POSITION), ts[order], step)
    back = np.empty_like(order)
    back[order] = np.arange(order.size)
    take_sol = {k: v[back[:n_take]] for k, v in sol.items()}
    ob_sol = {k: v[back[n_take:]] for k, v in sol.items()}

    # --- truth on the take's time base (section 1 columns + the pose)
    clean = meta["clean"]
    truth = {"t": t_take}
    for c in ("q", "u", "w", "theta", "p", "r", "v", "phi", "psi"):
        truth[c] = take_sol[c]
    for c in ("de", "dr"):
        truth[c] = clean[c][:n_take]
    truth["f"] = clean["f"][:n_take]
    for c in ("X", "Y", "Z", "L", "M", "N", "x", "y", "z", "qw", "qx", "qy", "qz"):
        truth[c] = take_sol[c]

    # --- the tracking take: pose noise and dropouts
    pos = np.column_stack([truth[c] for c in "xyz"]) + position_noise * rng.standard_normal((n_take, 3))
    q_true = np.column_stack([truth[c] for c in ("qw", "qx", "qy", "qz")])
    quat = quat_mul(q_true, _small_rotations(rng, n_take, np.deg2rad(attitude_noise)))
    lost = _dropouts(rng, n_take, dropouts, TRACKING["gap"])
    pos[lost] = np.nan
    quat[lost] = np.nan
    take = {"t": t_take, "position": pos, "quat": quat}
    for c in ("de", "dr", "f"):
        take[c] = truth[c] + NOISE[c] * rng.standard_normal(n_take)

    # --- the autopilot's log on its own clock
    log = None
    if onboard:
        trim, flap = meta["trim"], meta["flap"]
        rip = _ripple(flap.phase(s_ob), amp)
        log = {"t": t_ob}
        for j, c in enumerate(("de", "dr")):
            d = trim[c + "0"] + np.interp(s_ob, t_sim, meta["u_cmd"][:, j]) + rip[c]
            d = _measured(flight_kw, vehicle, s_ob, d)
            log[c] = d + NOISE[c] * rng.standard_normal(n_ob)
        log["f"] = flap.f(s_ob) + NOISE["f"] * rng.standard_normal(n_ob)
        for i, c in enumerate(("p", "q", "r")):
            log[c] = ob_sol[c] + bias[i] + ONBOARD["noise"] * rng.standard_normal(n_ob)

    info = {
        "clock_offset_s": offset if onboard else 0.0,  # one file holds both without a log
        "gyro_bias": bias.tolist(),
        "gyro_noise": ONBOARD["noise"],
        "dropouts": intervals(t_take, lost),
        "dropout_share": float(lost.mean()),
        "rate": float(rate),
        "onboard_rate": float(onboard_rate),
        "position_noise_m": float(position_noise),
        "attitude_noise_deg": float(attitude_noise),
        "start_position": list(START_POSITION),
        "integration_step_s": step,
        "model": "6-DOF nonlinear rigid body (fwid.synth._sixdof)",
    }
    truth_meta = dict(meta["truth"], raw=info)
    side = {"trim": meta["trim"], "first_input": meta["first_input"], "truth": truth_meta}
    return {"truth": truth, "take": take, "onboard": log, "lost": lost, "meta": side}


def _measured(flight_kw, vehicle, t, column):
    """The logged deflection under a `time-offset` effect (the logger trails), else as is."""
    from ._effects import Effect

    eff = flight_kw.get("effect", "none")
    if eff in ("none", None):
        return column
    e = eff if isinstance(eff, Effect) else Effect(eff, flight_kw.get("strength", 1.0), flight_kw.get("form"))
    return e.bind(vehicle).measured(t, column)
