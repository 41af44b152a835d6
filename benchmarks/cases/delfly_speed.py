"""The simulated problem that `speed.py` and `profile_fit.py` time: DelFly longitudinal flights.

Eq. (7) with the four bias terms (16 free parameters), 4.5 s at 200 Hz (900 samples),
elevator 3211 (even flights) or doublet (odd flights), white Gaussian measurement noise on
all four states. Flight i depends only on (seed, i), so it is the same at every size. The
equations are written out here again, in JAX (for the simulation and the hand-written
reference) and in numpy (for the scipy baseline), without fwid.

Importing this module imports fwid (which turns float64 on unless `FWID_NO_X64` is set),
records whether fwid did (`X64_BY_FWID`), and turns float64 on regardless: fwid.fit needs it.
Put the checkout's root first on `sys.path` before importing this, to time that fwid.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

import fwid

X64_BY_FWID = bool(jax.config.jax_enable_x64)
jax.config.update("jax_enable_x64", True)  # fwid.fit needs float64; say so in the output

from fwid.models import TABLE1  # noqa: E402

from peers.jax_output_error import rk4_scan  # noqa: E402

DT = 0.005  # 200 Hz
N_SAMPLES = 900  # 4.5 s
AERO = tuple(TABLE1)  # Xq Xu Xw Xde Zq Zu Zw Zde Mq Mu Mw Mde
BIASES = ("bq", "bu", "bw", "btheta")
NAMES = AERO + BIASES
TRUE = dict(TABLE1, bq=0.02, bu=-0.01, bw=0.015, btheta=-0.005)
NOISE_STD = (0.02, 0.005, 0.005, 0.002)  # q [rad/s], u [m/s], w [m/s], theta [rad]
# A plausible DelFly II: mass [kg], pitch inertia [kg m^2], trim u0, w0 [m/s], theta0 [rad].
DELFLY = dict(mass=0.0205, Iy=1.3e-4, g=9.81, u0=0.8, w0=0.3, theta0=1.2)
CONST_KEYS = ("mass", "Iy", "g", "u0", "w0", "theta0")


def vehicle_constants():
    """`fwid.synth.DELFLY` when fwid has one (with the keys this model needs), else ours."""
    try:
        import fwid.synth as synth

        d = synth.DELFLY
        vals = {k: float(d[k] if isinstance(d, dict) else getattr(d, k)) for k in CONST_KEYS}
        return vals, "fwid.synth.DELFLY"
    except Exception:
        return dict(DELFLY), "benchmarks/cases/delfly_speed.py DELFLY (fwid.synth.DELFLY not available)"


def lon_f_jax(x, u, th, c):
    """Eq. (7) with Eqs. (1), (3), (5) and the biases, written out again (no fwid)."""
    q, uu, w, tt = x[0], x[1], x[2], x[3]
    de = u[0]
    Xq, Xu, Xw, Xde, Zq, Zu, Zw, Zde, Mq, Mu, Mw, Mde, bq, bu, bw, bt = (th[i] for i in range(16))
    X = Xq * q + Xu * uu + Xw * w + Xde * de
    Z = Zq * q + Zu * uu + Zw * w + Zde * de
    M = Mq * q + Mu * uu + Mw * w + Mde * de
    return jnp.stack([
        M / c["Iy"] + bq,
        X / c["mass"] - c["w0"] * q - c["g"] * jnp.cos(c["theta0"]) * tt + bu,
        Z / c["mass"] + c["u0"] * q - c["g"] * jnp.sin(c["theta0"]) * tt + bw,
        q + bt,
    ])


def make_lon_f_numpy(c):
    """The same equations in numpy for the scipy baseline, `f(x, u, theta)`."""
    m, Iy, g, u0, w0 = c["mass"], c["Iy"], c["g"], c["u0"], c["w0"]
    ct, st = np.cos(c["theta0"]), np.sin(c["theta0"])

    def f(x, u, th):
        q, uu, w, tt = x
        de = u[0]
        Xq, Xu, Xw, Xde, Zq, Zu, Zw, Zde, Mq, Mu, Mw, Mde, bq, bu, bw, bt = th
        X = Xq * q + Xu * uu + Xw * w + Xde * de
        Z = Zq * q + Zu * uu + Zw * w + Zde * de
        M = Mq * q + Mu * uu + Mw * w + Mde * de
        return np.array([M / Iy + bq, X / m - w0 * q - g * ct * tt + bu,
                         Z / m + u0 * q - g * st * tt + bw, q + bt])

    return f


def elevator(t, kind, amp, pulse, t_on):
    """A 3211 (pulse widths 3-2-1-1 x `pulse`) or a doublet (2-2 x `pulse`), in rad."""
    pattern = [(3, 1), (2, -1), (1, 1), (1, -1)] if kind == "3211" else [(2, 1), (2, -1)]
    de = np.zeros_like(t)
    start = t_on
    for width, sign in pattern:
        end = start + width * pulse
        de[(t >= start - 1e-12) & (t < end - 1e-12)] = sign * amp
        start = end
    return de


def make_flights(n, seed, consts):
    """`n` simulated flights; flight i depends only on (seed, i)."""
    t = np.arange(N_SAMPLES) * DT
    theta_true = np.array([TRUE[k] for k in NAMES])
    us, x0s, cs, kinds = [], [], [], []
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        kind = "3211" if i % 2 == 0 else "doublet"
        amp = rng.uniform(0.05, 0.09) * (1 if rng.uniform() < 0.5 else -1)
        pulse = rng.uniform(0.15, 0.22)
        us.append(elevator(t, kind, amp, pulse, rng.uniform(0.3, 0.8))[:, None])
        x0s.append(np.zeros(4) if i == 0 else rng.normal(0.0, [0.05, 0.01, 0.01, 0.01]))
        c = dict(consts)
        if i > 0:  # trims differ a little from flight to flight
            c.update(u0=consts["u0"] * (1 + 0.05 * rng.normal()),
                     w0=consts["w0"] * (1 + 0.05 * rng.normal()),
                     theta0=consts["theta0"] + 0.03 * rng.normal())
        cs.append(c)
        kinds.append(kind)
    U, X0 = np.stack(us), np.stack(x0s)
    C = {k: np.array([c[k] for c in cs]) for k in CONST_KEYS}
    sim = jax.jit(jax.vmap(lambda u, x0, c: rk4_scan(lon_f_jax, jnp.asarray(theta_true), x0, u,
                                                      DT, c)))
    X = np.asarray(sim(jnp.asarray(U), jnp.asarray(X0), {k: jnp.asarray(v) for k, v in C.items()}))
    Z = np.empty_like(X)
    for i in range(n):
        rng = np.random.default_rng([seed, i, 1])
        Z[i] = X[i] + rng.normal(size=X[i].shape) * np.asarray(NOISE_STD)
    return dict(t=t, u=U, z=Z, x0=X0, consts=C, kinds=kinds, theta_true=theta_true,
                consts_list=cs)


def experiment(F, i):
    """Flight i of `make_flights`'s output as a `fwid.Experiment`."""
    return fwid.Experiment(F["t"], F["u"][i], F["z"][i], F["x0"][i], F["consts_list"][i])


def start_values(F, start):
    """The start of every method, `(n, 16)`: `"true1.2"` (true x 1.2) or `"least-squares"`
    (fwid's equation-error start of each flight)."""
    n = len(F["kinds"])
    if start == "true1.2":
        return np.tile(1.2 * F["theta_true"], (n, 1))
    m = fwid.longitudinal()
    return np.stack([np.asarray(fwid.least_squares_start(m, [experiment(F, i)]).theta())
                     for i in range(n)])


def setup(n, seed, start):
    """`n` flights and their starts: `(flights, starts (n, 16), problem)`, `problem` the
    description that goes into the results' JSON."""
    consts, consts_source = vehicle_constants()
    F = make_flights(n, seed, consts)
    problem = dict(
        model="fwid.longitudinal(): Eq. (7) + biases", free_parameters=list(NAMES),
        samples=N_SAMPLES, dt=DT, duration_s=N_SAMPLES * DT, inputs="elevator 3211 (even "
        "flights) / doublet (odd flights)", noise_std=dict(zip(("q", "u", "w", "theta"),
                                                             NOISE_STD)),
        true=dict(zip(NAMES, F["theta_true"].tolist())), constants=consts,
        constants_source=consts_source, start=start, seed=seed,
    )
    return F, start_values(F, start), problem
