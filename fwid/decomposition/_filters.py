"""Zero-phase Butterworth filters, applied in the frequency domain (Section III.B).

The paper low-pass filters the measurements at 40 Hz and splits them at 5 Hz with zero-phase
(forward-backward) Butterworth filters. Running an order-`N` digital Butterworth filter forwards and
backwards (`scipy.signal.filtfilt`, MATLAB `filtfilt`) multiplies the spectrum, in steady state, by
the *squared* magnitude of the filter:

$$|H(f)|^2 = \\frac{1}{1 + (\\tan(\\pi f\\,\\Delta t) / \\tan(\\pi f_c\\,\\Delta t))^{2N}}$$

(the bilinear transform with pre-warping puts the -3 dB point of each pass exactly at `f_c`; for
`f << 1/dt` this is the analogue `1 / (1 + (f/f_c)^(2N))`). Here that product is computed directly:
FFT, multiply by `|H|^2`, inverse FFT. The result is a smooth function of the cut-off, so it can be
jitted, vmapped, and differentiated with respect to `cutoff` (and `dt`).

**Edges.** The FFT treats the record as periodic, so a record whose ends do not match would ring
from both ends; the record is therefore extended by a full record length (`n - 1` samples) on each
side before the transform, the straight line through the two ends of the extended record is
subtracted (so it starts and ends at zero and can be zero-padded to a fast FFT length without a
jump) and added back afterwards. A straight line passes a zero-phase low-pass unchanged and is
removed by the complementary high-pass, so that step adds no error of its own. The extension
(`pad`) is one of:

- `"odd"`: odd reflection about each end point, `2 x[0] - x[k]` before the start and
  `2 x[-1] - x[-1-k]` after the end, as `filtfilt` pads; value and slope are continuous. The result
  equals `scipy.signal.sosfiltfilt(sos, x, padtype="odd", padlen=n - 1)` to rounding over the whole
  record (`filtfilt` with its default short padding differs only within a few `1 / cutoff` seconds
  of the ends, its own start-up transient). Right for slow, trend-like signals, but a signal that
  oscillates above the cut-off is reflected about whatever value the oscillation has at the last
  sample, so its low-passed part is off by up to the oscillation amplitude at the ends.
- `"even"`: even reflection, `x[k]` before the start; right for the oscillation, but turns a
  trend into a V at each end.
- `"hybrid"` (default): the low-passed part is continued by odd reflection and the remainder (the
  part above the cut-off) by even reflection, `odd(s) + even(x - s)`, with `s` found by a few
  fixed-point passes `s <- lowpass(odd(s) + even(x - s))`; it costs `1 + 6` FFT passes instead
  of one and is linear in `x`, so everything below still holds. The odd reflection of `s` turns
  about the slow part's *level* at each end, not its end sample: the straight line fitted to the
  samples near the end with weights `exp(-(time from the end) / T)`, `T = 0.1 / cutoff` (20 ms
  at 5 Hz), read at the end (`_end_weights`). Turning about the end sample would carry that
  sample's whole error into the low-passed value there; a record's ends are where loads
  reconstructed from tracked motion are least certain (one-sided data). `T` is the longest
  that keeps a slow signal's curvature from costing more at the ends (a 0.4 Hz sine of
  amplitude 0.5 on a trend: under 2e-3; 0.2 / cutoff gave 3e-3). On random flapping-like
  records (body motion at 0.3-2.5 Hz, a 12.3 Hz wing beat with a second harmonic, white noise
  0.02; split at 5 Hz, order 6; 40 records per class), the mean error of the cycle-averaged
  part at the end samples was 0.036 (slow part dominant, wing beat 0.1), 0.253 (wing beat
  1.0) and 0.080 (both alike, 0.3), against 0.033, 0.258 and 0.081 turning about the end
  sample; from 0.1 s in all agree (0.0035-0.0044). On simulated raw takes of 4.5 s without a
  gyro (0.4 mm, 0.15 deg; two sets of four), the worst flight's cycle-averaged Z error fell
  from 16.0 % and 17.5 % to 11.9 % and 14.0 % of its standard deviation, M from 21.7 % and
  13.6 % to 19.7 % and 12.3 %.

The low-pass and high-pass with the same cut-off and order are power complementary
(`|H_lp|^2 + |H_hp|^2 = 1`), so `highpass(x) == x - lowpass(x)` exactly: the two parts of a
split always add back to the input.
"""

from __future__ import annotations

import functools as ft

import jax
import jax.numpy as jnp
import numpy as np
import scipy.fft
from jaxtyping import Array, ArrayLike, Float

from .._errors import InputError


def _concrete(value) -> float | None:
    """`value` as a Python float when it is known at trace time, else `None`."""
    if isinstance(value, jax.core.Tracer):
        return None
    arr = np.asarray(value)
    if arr.size != 1:
        raise InputError(f"a cut-off frequency must be a scalar, got an array of shape {arr.shape}")
    return float(arr.reshape(()))


def check_cutoff(cutoff, dt, what: str = "cut-off") -> None:
    """Raise an `InputError` if a concrete `cutoff` is not in `(0, 1 / (2 dt))`; no-op if traced."""
    fc = _concrete(cutoff)
    step = _concrete(dt)
    if fc is None or step is None:
        return
    if not step > 0:
        raise InputError(f"the sample step dt must be positive, got {step!r}")
    nyquist = 0.5 / step
    if not (0.0 < fc < nyquist):
        raise InputError(
            f"{what} {fc:g} Hz must lie between 0 and the Nyquist frequency {nyquist:g} Hz "
            f"(sample step dt = {step:g} s)"
        )


def _as_float(x) -> Array:
    x = jnp.asarray(x)
    return x if jnp.issubdtype(x.dtype, jnp.floating) else x.astype(float)


@ft.cache
def _padded_length(n: int) -> int:
    return int(scipy.fft.next_fast_len(3 * n - 2, real=True))


def _log_ratio(m: int, dt, cutoff, prewarp: bool) -> Float[Array, " bins"]:
    """`log(f / f_c)` (pre-warped: `log(tan(pi f dt) / tan(pi f_c dt))`) on the rfft grid of
    length `m`; `-inf` at `f = 0`."""
    k = np.arange(m // 2 + 1)
    nonzero = k > 0
    if prewarp:
        # tan(pi f dt) with f = k / (m dt): the grid part does not depend on dt.
        # abs: at the Nyquist bin pi k / m may round to just above pi / 2, where tan < 0.
        grid = np.log(np.abs(np.tan(np.pi * np.where(nonzero, k, 1) / m)))
        grid = np.where(nonzero, grid, -np.inf)
        return jnp.asarray(grid) - jnp.log(jnp.tan(jnp.pi * cutoff * dt))
    grid = np.where(nonzero, np.log(np.where(nonzero, k, 1) / m), -np.inf)
    return jnp.asarray(grid) - jnp.log(dt) - jnp.log(cutoff)


def squared_gain(
    freqs: Float[ArrayLike, "*f"],
    dt: float | Float[ArrayLike, ""],
    cutoff: float | Float[ArrayLike, ""],
    *,
    order: int = 4,
    prewarp: bool = True,
) -> Float[Array, "*f"]:
    """The steady-state gain `|H(f)|^2` of the zero-phase order-`order` Butterworth low-pass.

    **Arguments:**

    - `freqs`: frequencies [Hz], in `[0, 1 / (2 dt)]`.
    - `dt`: sample step [s].
    - `cutoff`: cut-off frequency [Hz] (the gain is 1/2 there).
    - `order`: order `N` of the Butterworth filter run forwards and backwards.
    - `prewarp`: use the digital (bilinear, pre-warped) response, as `scipy.signal.butter`;
      `False` gives the analogue `1 / (1 + (f / f_c)^(2N))`.

    **Returns:** `|H(f)|^2`, same shape as `freqs`. The high-pass gain is `1 - |H(f)|^2`.
    """
    freqs = jnp.asarray(freqs, dtype=float)
    positive = freqs > 0
    safe = jnp.where(positive, freqs, 1.0)
    if prewarp:
        lr = jnp.log(jnp.abs(jnp.tan(jnp.pi * safe * dt))) - jnp.log(jnp.tan(jnp.pi * cutoff * dt))
    else:
        lr = jnp.log(safe) - jnp.log(cutoff)
    lr = jnp.where(positive, lr, -jnp.inf)
    return jax.nn.sigmoid(-2 * order * lr)


_PADS = ("hybrid", "odd", "even")
_HYBRID_PASSES = 6


#: Time constant of the end level's weights, in periods of the cut-off: `T = END_LEVEL / f_c`.
END_LEVEL = 0.1


def _end_weights(n: int, dt, cutoff, dtype):
    """The weights `a` (`(n,)`, from the end inwards) that read a record's level at its end,
    `sum(a x)`: the straight line fitted to the samples near the end by least squares with
    weights `exp(-(time from the end) / T)`, `T = END_LEVEL / f_c`, read at the end."""
    k = jnp.arange(n, dtype=dtype) * dt
    w = jnp.exp(-k * cutoff / END_LEVEL)
    s0, s1, s2 = jnp.sum(w), jnp.sum(w * k), jnp.sum(w * k * k)
    return (s2 - s1 * k) * w / (s0 * s2 - s1 * s1)


def _end_levels(x, a):
    """The slow part's level at each end of `x` (weights `a`, `_end_weights`). Linear in
    `x`; a record's one noisy end sample does not set it."""
    return jnp.sum(x * a, -1, keepdims=True), jnp.sum(x[..., ::-1] * a, -1, keepdims=True)


def _odd_about(x, head, tail):
    """Odd reflection about the levels `head`, `tail` of the two ends (`_end_levels`)."""
    n = x.shape[-1]
    return jnp.concatenate([2 * head - x[..., n - 1 : 0 : -1], x, 2 * tail - x[..., -2::-1]],
                           axis=-1)


def _odd(x):
    """Odd reflection about the end samples (`filtfilt`'s extension)."""
    return _odd_about(x, x[..., :1], x[..., -1:])


def _even(x):
    n = x.shape[-1]
    return jnp.concatenate([x[..., n - 1 : 0 : -1], x, x[..., -2::-1]], axis=-1)


@ft.partial(jax.jit, static_argnums=(3, 4, 5))
def _zero_phase_lowpass(x, dt, cutoff, order: int, prewarp: bool, pad: str):
    # Jitted once per (shape, order, prewarp, pad): eager calls run one compiled kernel, and new
    # cut-offs or steps do not recompile.
    n = x.shape[-1]
    if n < 2:
        return x
    m = _padded_length(n)
    gain = jax.nn.sigmoid(-2 * order * _log_ratio(m, dt, cutoff, prewarp))
    ramp = jnp.linspace(0.0, 1.0, 3 * n - 2, dtype=x.dtype)

    def filt(ext):
        # ext: the record extended by n - 1 samples on each side.
        line = ext[..., :1] + (ext[..., -1:] - ext[..., :1]) * ramp
        spectrum = jnp.fft.rfft(ext - line, n=m, axis=-1)
        out = jnp.fft.irfft(spectrum * gain, n=m, axis=-1)[..., : 3 * n - 2] + line
        return out[..., n - 1 : 2 * n - 1]

    if pad == "even":
        return filt(_even(x))
    if pad == "odd":
        return filt(_odd(x))
    a = _end_weights(n, dt, cutoff, x.dtype)
    s = filt(_odd_about(x, *_end_levels(x, a)))
    return jax.lax.fori_loop(
        0, _HYBRID_PASSES, lambda _, s: filt(_odd_about(s, *_end_levels(s, a)) + _even(x - s)), s
    )


def _check_pad(pad: str) -> str:
    if pad not in _PADS:
        raise InputError(f"pad must be one of {', '.join(map(repr, _PADS))}, got {pad!r}")
    return pad


def lowpass(
    x: Float[ArrayLike, "*channels n"],
    dt: float | Float[ArrayLike, ""],
    cutoff: float | Float[ArrayLike, ""],
    *,
    order: int = 4,
    prewarp: bool = True,
    pad: str = "hybrid",
) -> Float[Array, "*channels n"]:
    """Zero-phase Butterworth low-pass along the last axis (noise filter, cycle average).

    The noise filter and the cycle-average of Section III.B.

    Equivalent, away from the ends, to `scipy.signal.filtfilt` with `scipy.signal.butter(order,
    cutoff, fs=1/dt)` (everywhere, with `pad="odd"` and `padlen=n - 1`): the spectrum is
    multiplied by `|H(f)|^2` (see the module docstring), so there is no phase lag and the gain at
    `cutoff` is 1/2. Jit-able, vmap-able, differentiable with respect to `x`, `cutoff` and `dt`.

    **Arguments:**

    - `x`: samples, time along the last axis; any leading axes are channels (e.g. `(channels, n)`).
    - `dt`: sample step [s].
    - `cutoff`: cut-off frequency [Hz], in `(0, 1 / (2 dt))`; a float or a traced scalar.
    - `order`: Butterworth order `N` of each pass (static). The zero-phase response rolls off as
      `f^(-2N)`, i.e. `40 N` dB per decade. Default 4.
    - `prewarp`: digital (bilinear) response as `scipy.signal.butter` (default), or the analogue
      `1 / (1 + (f / f_c)^(2N))` if `False` (they differ only close to the Nyquist frequency).
    - `pad`: how the record is extended past its ends (static): `"hybrid"` (default), `"odd"`
      (as `filtfilt`) or `"even"`; see the module docstring.

    **Returns:** the low-passed signal, same shape as `x`.

    **Raises:** `fwid.InputError` if a concrete `cutoff` is not between 0 and the Nyquist frequency.
    """
    check_cutoff(cutoff, dt, "low-pass cut-off")
    return _zero_phase_lowpass(_as_float(x), dt, cutoff, int(order), bool(prewarp), _check_pad(pad))


def highpass(
    x: Float[ArrayLike, "*channels n"],
    dt: float | Float[ArrayLike, ""],
    cutoff: float | Float[ArrayLike, ""],
    *,
    order: int = 4,
    prewarp: bool = True,
    pad: str = "hybrid",
) -> Float[Array, "*channels n"]:
    """Zero-phase Butterworth high-pass along the last axis: `x - lowpass(x, dt, cutoff)`.

    The spectrum is multiplied by `1 - |H(f)|^2 = 1 / (1 + (f_c / f)^(2N))` (pre-warped), the
    squared magnitude of the order-`N` Butterworth high-pass, i.e. what `scipy.signal.filtfilt` with
    `scipy.signal.butter(order, cutoff, "highpass", fs=1/dt)` gives in steady state. Same arguments
    as [`fwid.decomposition.lowpass`][]. Low-pass plus high-pass is exactly `x`.

    **Arguments:** `x`, `dt`, `cutoff`, `order`, `prewarp`, `pad`: as
    [`fwid.decomposition.lowpass`][].

    **Returns:** the high-passed signal, same shape as `x`.
    """
    check_cutoff(cutoff, dt, "high-pass cut-off")
    x = _as_float(x)
    return x - _zero_phase_lowpass(x, dt, cutoff, int(order), bool(prewarp), _check_pad(pad))
