"""The DelFly as a rigid body: the full nonlinear 6-DOF equations of motion (pure JAX, diffrax).

The linear simulator (`_simulate.py`, paper Eqs. 7-9) is the small-motion limit of this one;
both see the same aerodynamic loads, the cycle-averaged Eqs. 1-6 (Tables 1 and 4) plus the
flapping Fourier series Eq. 12 (Table 7):

    F_aero = F0 + Fx dx + Fu u(t) + F_TV(phi_f(t)) + E(t)

with `F0` the trim loads, `dx = [u - u0, v, w - w0, p, q, r]` (the aerodynamics do not depend on
the attitude), `u(t)` the elevator and rudder perturbations and `E(t)` an injected effect's
extra load (both linear between their samples). Twelve states plus the quaternion's fourth
component, `y = [x y z | u v w | qw qx qy qz | p q r]`:

    m (V' + omega x V) = F_aero[:3] + m R^T [0, 0, g]         (body-axis forces)
    I omega' + omega x I omega = F_aero[3:],  I = [[Ix, 0, -Ixz], [0, Iy, 0], [-Ixz, 0, Iz]]
    quat' = 1/2 quat * (0, omega)                               (Hamilton, body -> NED)
    [x y z]' = R(quat) V                                        (north-east-down)

Integrated with diffrax's `Tsit5` at a constant step (`step`, 1/2000 s by default, a divisor
of the input's sample step) and read out at any times through the solver's dense output.
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._delfly import DELFLY, FORCES, STATES, DelFly, aero_matrices

#: State order of the 6-DOF model.
SIXDOF_STATES = ("x", "y", "z", "u", "v", "w", "qw", "qx", "qy", "qz", "p", "q", "r")

#: Where the flights start, NED [m]: 1.5 m above the floor of a tracking volume.
START_POSITION = (0.0, 0.0, -1.5)

_VEL = ("u", "v", "w", "p", "q", "r")


def quat_to_matrix(quat: Float[Array, "... 4"]) -> Float[Array, "... 3 3"]:
    """Rotation matrix body -> Earth of a Hamilton quaternion `[qw qx qy qz]` (any norm)."""
    quat = quat / jnp.linalg.norm(quat, axis=-1, keepdims=True)
    w, x, y, z = (quat[..., i] for i in range(4))
    rows = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    return jnp.stack([jnp.stack(r, axis=-1) for r in rows], axis=-2)


def euler_to_quat(phi, theta, psi) -> Float[Array, "... 4"]:
    """Quaternion body -> NED of 3-2-1 Euler angles (yaw `psi`, pitch `theta`, roll `phi`)."""
    cf, sf = jnp.cos(phi / 2), jnp.sin(phi / 2)
    ct, st = jnp.cos(theta / 2), jnp.sin(theta / 2)
    cp, sp = jnp.cos(psi / 2), jnp.sin(psi / 2)
    return jnp.stack([cp * ct * cf + sp * st * sf, cp * ct * sf - sp * st * cf,
                      cp * st * cf + sp * ct * sf, sp * ct * cf - cp * st * sf], axis=-1)


def quat_to_euler(quat) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """3-2-1 Euler angles `(phi, theta, psi)` of quaternions `(n, 4)` (numpy), roll and yaw
    unwrapped along the first axis (a branch continuous in time)."""
    q = np.asarray(quat, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    theta = np.arcsin(np.clip(2 * (w * y - x * z), -1.0, 1.0))
    phi = np.arctan2(2 * (y * z + w * x), 1 - 2 * (x * x + y * y))
    psi = np.arctan2(2 * (x * y + w * z), 1 - 2 * (y * y + z * z))
    return np.unwrap(phi, axis=0), theta, np.unwrap(psi, axis=0)


def _quat_mul(a, b):
    aw, ax, ay, az = a[0], a[1], a[2], a[3]
    bw, bx, by, bz = b[0], b[1], b[2], b[3]
    return jnp.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                      aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw])


class SixDof(eqx.Module):
    """The DelFly's nonlinear rigid-body dynamics with the synth's aerodynamic loads.

    Fields: `mass`, `g`, `inertia` (3 x 3 with the product of inertia `Ixz`), `V0` (trim body
    velocity `[u0, 0, w0]`), `F0` (trim loads), `Fx` (6 x 6 load derivatives over
    `[u v w p q r]`), `Fu` (6 x 2, `[de dr]`), `fourier` (3 x 2 x 6, Eq. 12 `[a_n, b_n]`), the
    flapping frequency's parameters (`f_start`, `slope`, jitter `amps`, `freqs`, `phases`,
    `phase0`, as `FlapFrequency`), and the sampled inputs `t_in` (uniform) / `u_in` (n x 2) /
    `e_in` (n x 6, extra loads).
    """

    mass: float
    g: float
    inertia: Float[Array, "3 3"]
    inertia_inv: Float[Array, "3 3"]
    V0: Float[Array, "3"]
    F0: Float[Array, "6"]
    Fx: Float[Array, "6 6"]
    Fu: Float[Array, "6 2"]
    fourier: Float[Array, "3 2 6"]
    flap_scalars: Float[Array, "3"]  # f_start, slope, phase0
    amps: Float[Array, " k"]
    freqs: Float[Array, " k"]
    phases: Float[Array, " k"]
    t_in: Float[Array, " n"]
    u_in: Float[Array, "n 2"]
    e_in: Float[Array, "n 6"]

    def phase(self, t):
        """Flapping phase `phase0 + 2 pi integral_0^t f` (as `FlapFrequency.phase`)."""
        f0, slope, phase0 = self.flap_scalars
        nu = 2 * jnp.pi * self.freqs
        cyc = f0 * t + 0.5 * slope * t * t + jnp.sum(
            self.amps / nu * (jnp.cos(self.phases) - jnp.cos(nu * t + self.phases)))
        return phase0 + 2 * jnp.pi * cyc

    def frequency(self, t):
        """Flapping frequency [Hz] at time `t`."""
        f0, slope, _ = self.flap_scalars
        return f0 + slope * t + jnp.sum(self.amps * jnp.sin(2 * jnp.pi * self.freqs * t + self.phases))

    def inputs(self, t):
        """`(u, e)`: the input perturbations and extra loads at `t`, linear between the
        samples (uniform in time)."""
        n = self.t_in.shape[0]
        dt = (self.t_in[-1] - self.t_in[0]) / (n - 1)
        s = (t - self.t_in[0]) / dt
        i = jnp.clip(jnp.floor(s).astype(int), 0, n - 2)
        a = s - i
        ue = jnp.concatenate([self.u_in, self.e_in], axis=1)
        v = (1 - a) * ue[i] + a * ue[i + 1]
        return v[:2], v[2:]

    def loads(self, t, y: Float[Array, "13"]) -> Float[Array, "6"]:
        """Aerodynamic loads `[X Y Z L M N]` in body axes at time `t` and state `y`."""
        dx = jnp.concatenate([y[3:6] - self.V0, y[10:13]])
        u, e = self.inputs(t)
        n = jnp.arange(1.0, 4.0)[:, None]
        ph = self.phase(t)
        flap = jnp.sum(self.fourier[:, 0] * jnp.sin(n * ph) + self.fourier[:, 1] * jnp.cos(n * ph), 0)
        return self.F0 + self.Fx @ dx + self.Fu @ u + flap + e

    def rhs(self, t, y, args=None):
        """`y'` of the rigid-body equations (module docstring)."""
        V, quat, om = y[3:6], y[6:10], y[10:13]
        R = quat_to_matrix(quat)
        F = self.loads(t, y)
        gb = R.T @ jnp.array([0.0, 0.0, self.g])
        Vd = F[:3] / self.mass + gb - jnp.cross(om, V)
        omd = self.inertia_inv @ (F[3:] - jnp.cross(om, self.inertia @ om))
        qd = 0.5 * _quat_mul(quat, jnp.concatenate([jnp.zeros(1), om]))
        return jnp.concatenate([R @ V, Vd, qd, omd])


def sixdof_model(flap, t_in, u_in, e_in=None, vehicle: DelFly = DELFLY) -> SixDof:
    """A `SixDof` for `vehicle` with the flapping frequency `flap` (a `FlapFrequency`), the
    elevator/rudder perturbations `u_in` (n x 2) at times `t_in` and extra loads `e_in`
    (n x 6, or `None`)."""
    Fx9, Fu = aero_matrices(vehicle)
    Fx = Fx9[:, [STATES.index(s) for s in _VEL]]
    trim = vehicle.trim()
    I = np.array([[vehicle.Ix, 0.0, -vehicle.Ixz], [0.0, vehicle.Iy, 0.0], [-vehicle.Ixz, 0.0, vehicle.Iz]])
    t_in = np.asarray(t_in, dtype=float)
    e_in = np.zeros((t_in.size, 6)) if e_in is None else np.asarray(e_in, dtype=float)
    return SixDof(
        mass=float(vehicle.mass), g=float(vehicle.g), inertia=jnp.asarray(I), inertia_inv=jnp.asarray(np.linalg.inv(I)),
        V0=jnp.array([vehicle.u0, 0.0, vehicle.w0]),
        F0=jnp.array([trim[k + "0"] for k in FORCES]), Fx=jnp.asarray(Fx), Fu=jnp.asarray(Fu),
        fourier=jnp.asarray(np.stack([vehicle.fourier(F) for F in FORCES], axis=-1)),
        flap_scalars=jnp.array([flap.f_start, flap.slope, flap.phase0]),
        amps=jnp.asarray(np.asarray(flap.amps, float)), freqs=jnp.asarray(np.asarray(flap.freqs, float)),
        phases=jnp.asarray(np.asarray(flap.phases, float)),
        t_in=jnp.asarray(t_in), u_in=jnp.asarray(np.asarray(u_in, dtype=float)), e_in=jnp.asarray(e_in),
    )


def initial_state(perturbation=None, vehicle: DelFly = DELFLY, position=START_POSITION) -> np.ndarray:
    """The 13-state `y0` at trim plus a perturbation (9 values in `STATES` order, the linear
    model's `[dq du dw dtheta dp dr dv dphi dpsi]`), at `position` (NED)."""
    d = dict(zip(STATES, np.zeros(9) if perturbation is None else np.asarray(perturbation, float)))
    quat = np.asarray(euler_to_quat(d["phi"], vehicle.theta0 + d["theta"], d["psi"]))
    return np.concatenate([np.asarray(position, float),
                           [vehicle.u0 + d["u"], d["v"], vehicle.w0 + d["w"]], quat,
                           [d["p"], d["q"], d["r"]]])


@eqx.filter_jit
def _solve(model, y0, ts, step, n_steps):
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(model.rhs), diffrax.Tsit5(), 0.0, ts[-1], step, y0,
        saveat=diffrax.SaveAt(ts=ts), stepsize_controller=diffrax.ConstantStepSize(),
        max_steps=n_steps)
    ys = sol.ys
    return ys, jax.vmap(model.loads)(ts, ys), jax.vmap(model.frequency)(ts), jax.vmap(model.phase)(ts)


def _bucket(n: int, size: int) -> int:
    return -(-n // size) * size


def _padded(model: SixDof) -> SixDof:
    """`model` with its input samples extended (same step, last values held) to a multiple
    of 1024 samples."""
    t = np.asarray(model.t_in)
    extra = _bucket(t.size, 1024) - t.size
    if extra == 0:
        return model
    dt = (t[-1] - t[0]) / (t.size - 1)
    t_new = np.concatenate([t, t[-1] + dt * np.arange(1, extra + 1)])
    hold = lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], extra, axis=0)])  # noqa: E731
    return eqx.tree_at(lambda m: (m.t_in, m.u_in, m.e_in), model,
                       (jnp.asarray(t_new), hold(model.u_in), hold(model.e_in)))


def integrate(model: SixDof, y0, ts, step: float = 1 / 2000) -> dict[str, np.ndarray]:
    """Integrate `model` from `y0` at t = 0 with a constant step `step` [s] (Tsit5) and read it
    out at the times `ts` (non-decreasing, >= 0; dense output between steps).

    **Arguments:**
    - `model`: a `SixDof` (`sixdof_model`).
    - `y0`: the 13 initial states (`initial_state`).
    - `ts`: output times [s].
    - `step`: integration step [s]; a divisor of the input sample step keeps the inputs'
      kinks on step boundaries.

    **Returns:** a dict of numpy arrays at `ts`: `t`, the `SIXDOF_STATES` (the quaternion
    normalised), `phi theta psi` (3-2-1, continuous), the aerodynamic loads `X Y Z L M N`,
    `f` (flapping frequency) and `phase` (flapping phase).
    """
    ts = np.asarray(ts, dtype=float)
    n = ts.size
    # shapes rounded up to buckets, so that takes of similar length share one compilation
    n_steps = _bucket(int(np.ceil(ts[-1] / step)) + 16, 8192)
    ts_pad = np.concatenate([ts, np.full(_bucket(n, 4096) - n, ts[-1])])
    ys, loads, f, phase = _solve(_padded(model), jnp.asarray(y0, dtype=float), jnp.asarray(ts_pad),
                                 float(step), n_steps)
    ys, loads, f, phase = ys[:n], loads[:n], f[:n], phase[:n]
    ys = np.array(ys)
    ys[:, 6:10] /= np.linalg.norm(ys[:, 6:10], axis=1, keepdims=True)
    out = {"t": ts}
    out.update({k: ys[:, i] for i, k in enumerate(SIXDOF_STATES)})
    out["phi"], out["theta"], out["psi"] = quat_to_euler(ys[:, 6:10])
    out.update({k: np.asarray(loads)[:, i] for i, k in enumerate(FORCES)})
    out["f"], out["phase"] = np.asarray(f), np.asarray(phase)
    return out
