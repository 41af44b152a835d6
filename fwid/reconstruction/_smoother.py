"""Noise levels by maximum likelihood, then the Rauch-Tung-Striebel smoother, for a batch
of independent problems of one length (takes, or takes x attitude axes, run together).

The noise levels come from the data: the smoother's cut-off `f_c` of the slow part, the
bandwidth `f_h` of the flapping coefficients and (with a gyro) the gyro's noise relative to
the attitude's are chosen on a grid (`_model.CUTOFFS`, ...) by the innovations'
log-likelihood, with the overall noise scale concentrated out (it is `mean(nu^2 / S)`);
the likelihood is evaluated on the take's most active `ML_WINDOW` samples (`_active_window`).
With `ends`, the smoother runs again with the slow acceleration at each problem's first and
last sample measured as the problem's own (`_end_prior`): a take's ends are seen from one
side only. The problems are split over the CPU devices (one per core, `fwid._jax_setup`).
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from . import _model as mdl

#: Samples used to choose the noise levels (the window where the slow motion is most active).
ML_WINDOW = 1000
#: Largest memory (bytes) of one call of the smoother, about three times its stored
#: covariances: the problems run in as few calls of one size as this allows (one call of
#: all of them runs faster per problem and step than several of a part).
GAIN_BYTES = 1.5e9

_JIT = {}


def _fns():
    """The compiled programs: `grid` (the log-likelihood of each problem at each grid point)
    and `smooth` (the smoothed totals, the gyro bias and the innovation statistics), both
    building the measurement rows and the inputs of the model from the flapping phase
    inside (no `(M, N, m, n)` array crosses to JAX). Each device runs its share of the
    problems (`_spread`, `shard_map`), vmapped as the last axis of the filter's arrays."""
    if not _JIT:
        import functools

        import jax
        import jax.numpy as jnp
        from jax.sharding import Mesh, PartitionSpec

        from ._kalman import concentrated_loglik, filter_stats, smooth

        lead = mdl.MIXING  # F = blockdiag(3 x 3, I): the structured products
        filter_stats = functools.partial(filter_stats, lead=lead)
        smooth = functools.partial(smooth, lead=lead)
        last = functools.partial(jnp.moveaxis, source=0, destination=-1)

        def model(phase, omega, rate, Z, u, n):
            bias = n == mdl.n_states(True)
            rows = mdl.rows(phase, omega, rate, bias, xp=jnp)
            H = [rows["pos"]] + ([rows["gyro"]] if bias else [])
            if Z.shape[-2] > len(H):  # the ends' prior on the slow acceleration (`_end_prior`)
                H.append(rows["acc"] * mdl.slow_mask(bias))
            return rows, jnp.stack(H, -2), u[:, None]  # (N, m, n); u: the first state's input

        def one_stats(F, Q, phase, omega, rate, R, Z, MK, u, m0, P0):
            _, H, U = model(phase, omega, rate, Z, u, F.shape[0])
            return jax.vmap(filter_stats, in_axes=(None, -1, None, -1, None, None, None, None,
                                                   None))(F, Q, H, R, Z, MK, U, m0, P0)

        def one_smooth(F, Q, phase, omega, rate, R, Z, MK, u, m0, P0):
            rows, H, U = model(phase, omega, rate, Z, u, F.shape[0])
            x, st = smooth(F, Q, H, R, Z, MK, U, m0, P0)
            out = [jnp.einsum("kn,knc->kc", rows[k], x) for k in ("pos", "vel", "acc")]
            return (*out, x[0, -1, :], st, x[:, :3, :])  # the last: the slow part alone

        # the problems (and the grid's points) vmapped as the last axes: see `_kalman`
        batched = (None, -1, -1, -1, None, -1, -1, -1, -1, -1, None)
        stats = jax.vmap(one_stats, in_axes=batched[:5] + (None,) + batched[6:])

        def grid(F, Q, phase, omega, rate, R, Z, MK, u, m0, P0):
            # Q (M, G, n, n), R (G, m)
            Q, R = jnp.moveaxis(Q, (0, 1), (-1, -2)), R.T
            a = [last(x) for x in (phase, omega, Z, MK, u, m0)]
            return concentrated_loglik(stats(F, Q, *a[:2], rate, R, *a[2:], P0))

        def smoothed(F, Q, phase, omega, rate, R, Z, MK, u, m0, P0):
            a = [last(x) for x in (Q, phase, omega, R, Z, MK, u, m0)]
            return jax.vmap(one_smooth, in_axes=batched)(F, *a[:3], rate, *a[3:], P0)

        mesh = Mesh(np.array(jax.devices()), ("b",))
        b, r = PartitionSpec("b"), PartitionSpec()
        spread = functools.partial(jax.shard_map, mesh=mesh, out_specs=b, check_vma=False)
        _JIT["grid"] = jax.jit(spread(grid, in_specs=(r, b, b, b, r, r, b, b, b, b, r)))
        _JIT["smooth"] = jax.jit(spread(smoothed, in_specs=(r, b, b, b, r, b, b, b, b, b, r)))
    return _JIT


def cycle_samples(omega: np.ndarray, dt: float, default: int) -> int:
    """Samples in one flapping cycle at the median of the angular frequency `omega` (rad/s),
    or `default` where it has no finite positive value."""
    w0 = np.nanmedian(omega) if np.isfinite(omega).any() else np.nan
    return int(round(2 * np.pi / (w0 * dt))) if np.isfinite(w0) and w0 > 0 else default


def _cycle_mean(y: np.ndarray, w: int) -> np.ndarray:
    """`y` `(N, c)` averaged over `w` samples, twice (centred, edges held): the flapping
    harmonics of a period of about `w` samples cancel, the slow motion stays. With `w` even
    one average lags by half a sample and the other leads by as much, so the two are centred
    (the same way twice shifted a path at 1 m/s by 5 mm at 200 Hz)."""
    for lead in (w // 2, w - 1 - w // 2):
        pad = np.pad(y, ((lead, w - 1 - lead), (0, 0)), mode="edge")
        c = np.cumsum(np.concatenate([np.zeros((1, y.shape[1])), pad]), 0)
        y = (c[w:] - c[:-w]) / w
    return y


def _active_window(z, u, mask, dt, lengths=None, omega=None) -> np.ndarray:
    """Sample indices `(M, W)` of each problem's most active `ML_WINDOW` samples, where the
    noise levels are chosen: the window where the slow (cycle-averaged) motion accelerates
    most. The measured path (`z` less the summed inputs `u`) is averaged over one flapping
    cycle (twice, `omega` the flapping angular frequency `(M, N)`; 0.1 s without it), and
    its second difference over one cycle squared: the manoeuvre, not the flapping (which is
    as large in steady flight), decides; a take that is quiet but for its manoeuvre must be
    smoothed as its manoeuvre needs, whatever its length. `lengths` `(M,)`: each problem's
    own samples (the rest pads it to the batch's length), all by default."""
    M, N = mask.shape
    W = min(N, ML_WINDOW)
    lengths = np.full(M, N) if lengths is None else np.asarray(lengths, int)
    path = np.where(mask[..., None], z, np.nan) - np.cumsum(u, axis=1)
    out = np.empty((M, W), int)
    without = int(round(0.1 / dt))  # the cycle's samples without a flapping frequency
    for m in range(M):
        L = int(lengths[m])  # this problem's own samples
        k = without if omega is None else cycle_samples(omega[m, :L], dt, without)
        k = max(1, min(k, L // 8))
        y = path[m, :L]
        good = np.isfinite(y[:, 0])
        y = np.stack([np.interp(np.arange(L), np.flatnonzero(good), c[good]) for c in y.T], 1)
        sm = _cycle_mean(y, k)
        a = np.zeros(L)
        if L > 2 * k:
            a[k:-k] = np.sum((sm[2 * k:] - 2 * sm[k:-k] + sm[:-2 * k]) ** 2, 1)
        a[:2 * k], a[L - 2 * k:] = 0.0, 0.0  # the averages' edges
        c = np.concatenate([[0.0], np.cumsum(a)])
        start = int(np.argmax(c[W:] - c[:-W])) if L > W else 0  # past L: the padding
        out[m] = np.arange(start, start + W)
    return out


def _spread(*arrays):
    """The arrays (batch first) on every CPU device, split along the batch (padded with
    copies of the last problem to a multiple of the device count): XLA then runs each
    device's share of the problems on its own core. Returns the arrays and the batch."""
    import jax
    from jax.sharding import Mesh, NamedSharding, PartitionSpec

    M = arrays[0].shape[0]
    devices = jax.devices()
    if len(devices) < 2:
        return [jax.numpy.asarray(a) for a in arrays], M
    pad = (-M) % len(devices)
    sharding = NamedSharding(Mesh(np.array(devices), ("b",)), PartitionSpec("b"))
    out = [np.concatenate([a, np.repeat(a[-1:], pad, 0)]) if pad else a for a in arrays]
    return [jax.device_put(a, sharding) for a in out], M


class Smoothed(NamedTuple):
    """Smoothed totals `(M, N, c)` (slow part plus harmonics), the slow part alone, and the
    chosen noise levels."""

    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    bias: np.ndarray | None  # (M, c)
    sigma: np.ndarray        # (M,) noise std of position/attitude measurements
    sigma_gyro: np.ndarray | None
    cutoff: np.ndarray       # (M,) Hz
    coeff_bandwidth: np.ndarray  # (M,) Hz
    params: list             # (cutoff, coeff_bandwidth, gyro_ratio) per problem
    slow: np.ndarray | None = None  # (M, N, 3, c): the slow part's value, rate, acceleration


def _end_prior(slow, s2, lengths):
    """The slow part's acceleration at a take's ends, as the take's own (empirical Bayes):
    its mean `(M, c)` over each problem's middle 80 % and that stretch's variance (averaged
    over the columns) in units of the measurement noise's, `(M,)`."""
    mean, var = [], []
    for m, L in enumerate(lengths):
        a = slow[m, L // 10:L - L // 10, 2, :]
        mean.append(np.mean(a, 0))
        var.append(max(float(np.mean(np.var(a, 0))), 1e-30) / max(float(s2[m]), 1e-30))
    return np.array(mean), np.array(var)


def smooth_batch(z, mask, phase, omega, dt: float, *, gyro=None, gyro_mask=None, u=None,
                 ends: bool = True, scale: float = 1e-6, params=None,
                 lengths=None) -> Smoothed:
    """Smooth `M` independent problems of one length `N`, each with `c` data columns that
    share the noise levels.

    **Arguments:**
    - `z` `(M, N, c)`: position (attitude) measurements; `mask` `(M, N)`: where they exist;
    - `phase`, `omega` `(M, N)`: flapping phase and angular frequency (`_model.phase_of`);
    - `dt`: sample step (s);
    - `gyro` `(M, N, c)`, `gyro_mask` `(M, N)`: rate measurements (with a bias state), or None;
    - `u` `(M, N, c)`: known input of the first state per step (the attitude's nominal
      increment), or None;
    - `ends`: smooth each end again with its slow acceleration held to the take's own
      (`_end_prior`; the motion at an end is seen from one side only, and the white-jerk
      model's diffuse start leaves its acceleration there free);
    - `scale`: the measurement variance guessed, for the diffuse prior;
    - `params`: `(cutoff, coeff_bandwidth, gyro_ratio)` per problem to skip the search;
      with `gyro_ratio` None, only the gyro's noise is searched;
    - `lengths` `(M,)`: the samples of each problem, where problems of several lengths are
      padded to one `N` (the padding unmeasured: `mask`, `gyro_mask` False, `omega` NaN,
      `u` 0, which leaves the smoothed samples before it exactly as they were; one compiled
      program for all); default: all `N`.

    **Returns:** a `Smoothed`.
    """
    import jax.numpy as jnp

    fns = _fns()
    z = np.asarray(z, float)
    M, N, c = z.shape
    bias = gyro is not None
    n = mdl.n_states(bias)
    rate = 1.0 / dt
    m_meas = 2 if bias else 1
    phase, omega = np.asarray(phase, float), np.asarray(omega, float)
    Z = np.stack([np.nan_to_num(z)] + ([np.nan_to_num(gyro)] if bias else []), 2)
    MK = np.stack([mask] + ([gyro_mask] if bias else []), 2).astype(bool)
    u = np.zeros((M, N, c)) if u is None else np.asarray(u, float)
    F = mdl.transition(dt, bias)
    P0 = mdl.prior(n, bias, scale)
    m0 = np.zeros((M, n, c))
    first = np.argmax(mask, axis=1)
    m0[:, 0, :] = z[np.arange(M), first]
    omega0 = np.array([np.nanmedian(o) if np.isfinite(o).any() else 2 * np.pi for o in omega])
    F_, P0_, rate_ = jnp.asarray(F), jnp.asarray(P0), jnp.asarray(rate)

    def noise(fc, fh, w0, ratio):
        qj, qh = mdl.intensities(dt, fc, fh, w0)
        return mdl.process_noise(dt, qj, qh, bias), np.array([1.0, ratio**2][:m_meas])

    if params is None or any(p[2] is None for p in params):
        if params is None:
            grid = [list(itertools.product(mdl.CUTOFFS, mdl.COEFF_BANDWIDTHS,
                                           mdl.GYRO_RATIOS if bias else (1.0,)))] * M
        else:  # the motion's levels known (from the attitude alone): the gyro's noise only
            grid = [[(p[0], p[1], g) for g in mdl.GYRO_RATIOS] for p in params]
        idx = _active_window(z, u, mask, dt, lengths, omega)  # (M, W)
        take = lambda a: np.take_along_axis(a, idx.reshape(idx.shape + (1,) * (a.ndim - 2)), 1)  # noqa: E731
        Qs = np.stack([[noise(fc, fh, w0, g)[0] for fc, fh, g in gm] for gm, w0 in zip(grid, omega0)])
        Rs = np.stack([noise(1, 1, 1, g)[1] for _, _, g in grid[0]])
        if any(gm != grid[0] for gm in grid):  # gyro ratios only: the same for every problem
            assert all([g for *_, g in gm] == [g for *_, g in grid[0]] for gm in grid)
        m0w = m0.copy()
        fw = np.argmax(take(mask), axis=1)
        m0w[:, 0, :] = take(z)[np.arange(M), fw]
        (Qs, phw, omw, Zw, MKw, uw, m0w), _ = _spread(Qs, take(phase), take(omega), take(Z),
                                                      take(MK), take(u), m0w)
        ll = np.asarray(fns["grid"](F_, Qs, phw, omw, rate_, jnp.asarray(Rs), Zw, MKw, uw, m0w,
                                    P0_))[:M]
        best = np.argmax(np.where(np.isfinite(ll), ll, -np.inf), axis=1)
        params = [gm[b] for gm, b in zip(grid, best)]
    Q = np.stack([noise(fc, fh, w0, g)[0] for (fc, fh, g), w0 in zip(params, omega0)])
    R = np.stack([noise(1, 1, 1, g)[1] for _, _, g in params])
    most = max(2, int(GAIN_BYTES // (N * n * n * 8 * 3)))  # problems per call at most
    chunk = -(-M // -(-M // most))  # as many per call as that allows, in calls of one size

    def run(Q, phase, omega, R, Z, MK, u, m0):
        parts = []
        for a in range(0, len(Q), chunk):
            s = slice(a, a + chunk)
            args, m = _spread(Q[s], phase[s], omega[s], R[s], Z[s], MK[s], u[s], m0[s])
            res = fns["smooth"](F_, *args[:3], rate_, *args[3:], P0_)
            parts.append([np.asarray(r)[:m] for r in res])
        return [np.concatenate(p) for p in zip(*parts)]

    pos, vel, acc_, b, acc, slow = run(Q, phase, omega, R, Z, MK, u, m0)
    s2 = acc[:, 1] / np.maximum(acc[:, 2], 1)  # the concentrated noise scale
    if ends:  # again, each end held to the take's own slow acceleration (`_end_prior`)
        lens = np.full(M, N) if lengths is None else np.asarray(lengths, int)
        mean, var = _end_prior(slow, s2, lens)
        Zp, MKp = np.zeros((M, N, 1, c)), np.zeros((M, N, 1), bool)
        for m, L in enumerate(lens):
            Zp[m, [0, L - 1], 0], MKp[m, [0, L - 1], 0] = mean[m], True
        pos, vel, acc_, b, _, slow = run(Q, phase, omega, np.concatenate([R, var[:, None]], 1),
                                         np.concatenate([Z, Zp], 2),
                                         np.concatenate([MK, MKp], 2), u, m0)
    out = {"pos": pos, "vel": vel, "acc": acc_}
    ratio = np.array([p[2] for p in params])
    return Smoothed(out["pos"], out["vel"], out["acc"], b if bias else None,
                    np.sqrt(s2), np.sqrt(s2) * ratio if bias else None,
                    np.array([p[0] for p in params]), np.array([p[1] for p in params]),
                    list(params), slow)
