"""The flapping frequency from the pose's own flapping ripple, for takes where nothing logged
it (a tracking-only take).

Flapping rocks the body at the flapping frequency: the body rates (finite differences of the
tracked attitude) carry a line there and at its harmonics. The take's spectrum (Welch, per
axis) gives the fundamental within `BAND` (Hz, the plausible range of flapping vehicles, up to
0.45 times the sample rate) whose harmonics stand out most together (`_harmonic_score`). A
bin's prominence is its power over the local noise floor (the median within `LOCAL` Hz: the
rates' noise rises with frequency); a line counts when it stands `PROMINENCE` of the Welch
noise's standard deviations above that floor. The candidate is checked against its
subharmonics: where `f/2` (or `f/3`) is a line too and its harmonic series explains the ripple
as well, the fundamental is `f/2` (a body that rocks mostly at twice the wing beat is read at
the wing beat); a take that shows one line only is read at that line. A fundamental at the
band's edge is kept with a warning naming the range. Short-time spectra (`WINDOW` s, a quarter
overlapping) then follow it through the take within `TRACK` of it, each peak refined by a
parabola through its three bins' log power, and the result is interpolated onto the samples.
"""

from __future__ import annotations

import numpy as np

from ._rotations import log_so3, tracked_matrices

#: The band searched for the flapping line (Hz): the plausible range of flapping vehicles,
#: from large ornithopters (~5 Hz) to insect-scale robots (~60 Hz).
BAND = (5.0, 60.0)
#: Width (Hz) each side of a bin over which its local noise floor is the median.
LOCAL = 5.0
#: How far a line must stand above the local median spectral level, in standard deviations
#: of a Welch spectrum's noise bins (`1 / sqrt(K)` of the level for `K` segments averaged).
PROMINENCE = 8.0
#: Short-time window (s) and the fraction of the line's frequency it may wander.
WINDOW = 2.0
TRACK = 0.3


def _rates(t, quat, tracked):
    R = tracked_matrices(quat, tracked)
    dt = float(np.median(np.diff(t)))
    w = log_so3(np.swapaxes(R[:-1], -1, -2) @ R[1:]) / dt
    ok = tracked[:-1] & tracked[1:]
    w = np.where(ok[:, None], w, 0.0)
    return w - np.mean(w[ok], 0) if ok.any() else w, dt


def _prominence(freq, power):
    """Each bin's power over the local noise floor: the median of the bins within `LOCAL` Hz
    (per axis). Finite differences of a noisy attitude give rates whose noise rises with
    frequency, so a floor of the whole band would make any high bin look like a line."""
    from scipy.ndimage import median_filter

    df = freq[1] - freq[0]
    size = 2 * max(2, int(round(LOCAL / df))) + 1
    level = median_filter(power, size=(size,) + (1,) * (power.ndim - 1), mode="nearest")
    return power / np.where(level > 0, level, np.inf)


def _series(prom, freq, cand, top, floor):
    """For each candidate fundamental (bin indices `cand`): the summed log prominence of its
    harmonics 1-3 below `top` Hz where they reach `floor` (below it, noise: nothing), and
    the largest prominence among them; zero for a candidate that is not a line itself (a
    fundamental is seen at its own frequency, not only through its multiples)."""
    lp = np.log(np.maximum(prom, 1.0)) * (prom >= floor)
    df = freq[1] - freq[0]
    score = np.zeros(cand.size)
    best_prom = np.zeros(cand.size)
    for k in range(1, 4):
        inside = k * freq[cand] <= top
        idx = np.clip(np.rint(k * freq[cand] / df).astype(int), 1, len(freq) - 2)
        near = np.maximum(np.maximum(lp[idx - 1], lp[idx]), lp[idx + 1])  # (cand, axes)
        score += np.where(inside, near.sum(-1), 0.0)
        pk = np.maximum(np.maximum(prom[idx - 1], prom[idx]), prom[idx + 1]).max(-1)
        best_prom = np.maximum(best_prom, np.where(inside, pk, 0.0))
        if k == 1:
            own = near.max(-1) > 0
    return np.where(own, score, 0.0), np.where(own, best_prom, 0.0)


def _harmonic_score(freq, power, lo, hi, top, floor):
    """The fundamental in `[lo, hi]` whose harmonics 1-3 (those below `top` Hz) stand out
    most (`_series`, prominence over the local floor `_prominence`), checked against its
    subharmonics: where `f/2` (or `f/3`) is itself a line (prominence `floor` or more) and
    its own series explains the ripple as well, the fundamental is `f/2` (a body that
    rocks mostly at twice the flapping frequency, two wings beating in opposition, is read
    at the flapping frequency). Returns the fundamental (refined by a parabola through the
    log power of its line's bins) and the largest prominence among its harmonics."""
    prom = _prominence(freq, power)
    df = freq[1] - freq[0]
    cand = np.flatnonzero((freq >= lo) & (freq <= hi))
    if cand.size < 3:
        return np.nan, 0.0
    score, best_prom = _series(prom, freq, cand, top, floor)
    j = int(np.argmax(score))
    for m in (2, 3):
        sub = int(np.argmin(np.abs(freq[cand] - freq[cand[j]] / m)))
        if abs(freq[cand[sub]] - freq[cand[j]] / m) > df or sub == j:
            continue
        i = cand[sub]
        line = np.max(prom[max(i - 1, 0):i + 2]) >= floor
        if line and score[sub] >= score[j] - 1e-9:
            j = sub
            break
    # the line's own peak near the fundamental, refined by a parabola through log power
    i = cand[j]
    total = power.sum(-1) if power.ndim > 1 else power
    i = max(1, min(len(freq) - 2, i - 1 + int(np.argmax(total[max(i - 1, 0):i + 2]))))
    f = float(freq[i])
    a, b, c = np.log(np.maximum(total[i - 1:i + 2], 1e-300))
    den = a - 2 * b + c
    if den < 0:
        f += float(np.clip(0.5 * (a - c) / den, -0.5, 0.5)) * df
    return f, float(best_prom[j])


def _threshold(n: int, nper: int) -> float:
    """The prominence a line needs in a Welch spectrum of `n` samples in segments of `nper`
    (half overlapping): `PROMINENCE` noise standard deviations above the level."""
    segments = max(1, 2 * n // nper - 1)
    return 1.0 + PROMINENCE / np.sqrt(segments)


def flapping_frequency(t: np.ndarray, quat: np.ndarray, tracked: np.ndarray):
    """The flapping frequency (Hz) at each sample of a take from its attitude ripple, or
    None when the take shows no flapping line (module docstring).

    **Returns:** `(f, note)`: `f` `(n,)` or None, and a one-line note for the take's
    warnings."""
    from scipy.signal import welch

    w, dt = _rates(t, quat, tracked)
    fs = 1.0 / dt
    hi = min(BAND[1], 0.45 * fs)
    nper = min(len(w), int(round(WINDOW * fs)))
    if nper < 16 or hi <= BAND[0]:
        return None, "no flapping frequency: the take is too short or too slowly sampled to see it"
    freq, p = welch(w, fs=fs, nperseg=nper, axis=0)
    need = _threshold(len(w), nper)
    f0, prom = _harmonic_score(freq, p, BAND[0], hi, 0.45 * fs, need)
    if not np.isfinite(f0) or prom < need:
        return None, ("no flapping line in the pose's body rates (none between "
                      f"{BAND[0]:g} and {hi:.3g} Hz stands out); the flights have no f column "
                      "and no flapping harmonics are separated: map f from the log if it has it")
    hop = max(1, nper // 4)
    centres, track = [], []
    for s in range(0, len(w) - nper + 1, hop):
        fr, ps = welch(w[s:s + nper], fs=fs, nperseg=nper, axis=0)
        fk, pk = _harmonic_score(fr, ps, f0 * (1 - TRACK), f0 * (1 + TRACK), 0.45 * fs,
                                 _threshold(nper, nper))
        if np.isfinite(fk) and pk >= _threshold(nper, nper):
            centres.append(t[s] + 0.5 * nper * dt)
            track.append(fk)
    f = (np.full(len(t), f0) if len(track) < 2
         else np.interp(t, np.array(centres), np.array(track)))
    note = (f"flapping frequency from the pose's ripple: {np.median(f):.3g} Hz "
            f"(from {f.min():.3g} to {f.max():.3g}); no log gave f")
    df = freq[1] - freq[0]
    if f0 <= BAND[0] + df or f0 >= hi - df:
        note += (f"; it lies at the edge of the {BAND[0]:g}-{hi:.3g} Hz searched (flapping "
                 "vehicles beat at 5-60 Hz): check it, or map f from the log")
    return f, note
