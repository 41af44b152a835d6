"""The flapping frequency from tracked wings: a take that tracks the wings as rigid bodies of
their own (`FlapperLeftWing`, `FlapperRightWing`, any rigid body whose name holds "wing")
gives the flapping frequency directly, where no autopilot log does.

Each wing's attitude relative to the body's, `R_body^T R_wing`, swings about the hinge once a
wing beat: its rotation vector's principal component (the stroke angle) is band-passed about
its spectral line (`BAND`, Hz, up to 0.45 times the sample rate), and the phase of its analytic
signal (Hilbert) advances `2 pi f` a second. The frequency is that phase's slope, averaged over
one beat and over the wings, held at the ends and across the frames a wing was lost.
"""

from __future__ import annotations

import numpy as np

from ._rotations import log_so3

#: The band searched for the wing beat (Hz).
BAND = (2.0, 60.0)
#: The band-pass about the line: this fraction of its frequency either side.
HALF_WIDTH = 0.4
#: Least share of the frames a wing must be tracked on to be used.
MIN_TRACKED = 0.5


def stroke_angle(R_body: np.ndarray, R_wing: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """The wing's stroke angle (rad, mean removed; NaN where not `ok`): the principal
    component of the rotation vector of `R_body^T R_wing`."""
    v = log_so3(np.swapaxes(R_body[ok], -1, -2) @ R_wing[ok])
    v = v - v.mean(0)
    _, _, vt = np.linalg.svd(v, full_matrices=False)
    out = np.full(len(ok), np.nan)
    out[ok] = v @ vt[0]
    return out


def beat_frequency(t: np.ndarray, angle: np.ndarray) -> np.ndarray | None:
    """The instantaneous beat frequency (Hz) of a stroke angle (NaN where lost), or None
    when it shows no line in `BAND`."""
    from scipy import signal

    ok = np.isfinite(angle)
    dt = float(np.median(np.diff(t)))
    fs = 1.0 / dt
    x = np.interp(np.arange(len(t)), np.flatnonzero(ok), angle[ok])
    hi = min(BAND[1], 0.45 * fs)
    freq, p = signal.welch(x, fs=fs, nperseg=min(len(x), int(round(2.0 * fs))))
    band = (freq >= BAND[0]) & (freq <= hi)
    if band.sum() < 3:
        return None
    f0 = float(freq[band][np.argmax(p[band])])
    if p[band].max() < 10.0 * np.median(p[band]):
        return None
    lo, up = f0 * (1 - HALF_WIDTH), min(f0 * (1 + HALF_WIDTH), 0.49 * fs)
    sos = signal.butter(4, [lo, up], btype="band", fs=fs, output="sos")
    phase = np.unwrap(np.angle(signal.hilbert(signal.sosfiltfilt(sos, x))))
    f = np.gradient(phase, dt) / (2 * np.pi)
    w = max(1, int(round(fs / f0)))
    f = np.convolve(np.pad(f, (w // 2, w - 1 - w // 2), mode="edge"), np.ones(w) / w, "valid")
    return np.clip(f, lo, up)


def wing_frequency(t, R_body, body_ok, wings: dict):
    """The flapping frequency (Hz) on `t` from the tracked wings `wings` (`name -> (R, ok)`,
    body -> world matrices and the frames each is tracked on), averaged over the wings that
    show a beat; `(f or None, note)`."""
    found, names = [], []
    for name, (R, ok) in wings.items():
        both = ok & body_ok
        if both.mean() < MIN_TRACKED:
            continue
        f = beat_frequency(t, stroke_angle(R_body, R, both))
        if f is not None:
            found.append(f)
            names.append(name)
    if not found:
        return None, ""
    f = np.mean(found, 0)
    return f, (f"flapping frequency from the tracked wings ({', '.join(names)}): "
               f"{np.median(f):.3g} Hz (from {f.min():.3g} to {f.max():.3g})")
