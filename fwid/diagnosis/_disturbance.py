"""Is what is left a random disturbance? The colour of the cycle-averaged residual.

When neither a catalogue effect nor a probe predicts the held-out error, it is either
measurement noise (the model is adequate) or a disturbance that nothing measured predicts
(gusts, process noise). They differ in colour. Loads reconstructed from the motion carry the
states' measurement noise differentiated (Section III): within the cycle-averaged band its
spectrum is flat or rises with frequency. A disturbance force is strongest at the low
frequencies where gusts and turbulence have their energy (Dryden, von Karman) and falls off.
`redness` is the ratio of the residual's mean power spectral density in `LOW_HZ` to that in
`HIGH_HZ` (both inside the band below the split), pooled over the axis's loads and flights.

White noise gives 1, differentiated noise less; `RED_MIN` leaves room for the scatter of a
few flights' periodograms. The same ratio decides whether a probe that predicts part of the
residual found structure or only a proxy of the disturbance: a state that integrates the
disturbance (the attitude after a gust) predicts part of it, but leaves the rest as red as
before, where a deterministic term, once fitted, leaves the noise.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.signal import periodogram

#: Frequency bands [Hz] compared.
LOW_HZ = (0.2, 1.5)
HIGH_HZ = (2.5, 4.5)
#: A residual at least this red is a disturbance (or deterministic structure).
RED_MIN = 2.0
#: Bands [Hz] of the spectrum reported.
SPECTRUM_HZ = ((0.2, 0.5), (0.5, 1.0), (1.0, 1.5), (1.5, 2.5), (2.5, 3.5), (3.5, 4.5))


def band_psd(x: np.ndarray, dt: float, bands=(LOW_HZ, HIGH_HZ)) -> list[float]:
    """Mean power spectral density of `x` in each of `bands` (Hann periodogram)."""
    f, p = periodogram(x - np.mean(x), fs=1.0 / dt, window="hann")
    out = []
    for lo, hi in bands:
        sel = p[(f >= lo) & (f <= hi)]
        out.append(float(np.mean(sel)) if sel.size else 0.0)
    return out


def colour(residuals: Sequence[dict], dts: Sequence[float], loads: Sequence[str],
           scale: dict) -> dict:
    """`redness` (low/high PSD ratio) of the residuals (per flight, by load), each load scaled
    by `scale[load]` (its baseline mean square) before pooling; with the pooled PSDs."""
    lo = hi = 0.0
    for res, dt in zip(residuals, dts):
        for ld in loads:
            a, b = band_psd(res[ld], dt)
            lo += a / scale[ld]
            hi += b / scale[ld]
    return {"redness": lo / hi if hi > 0 else float("inf"), "low_hz": list(LOW_HZ),
            "high_hz": list(HIGH_HZ)}


def spectrum(residuals: Sequence[dict], dts: Sequence[float], loads: Sequence[str]) -> dict:
    """The residuals' size and spectrum by load: RMS and the mean PSD in `SPECTRUM_HZ`
    (averaged over the flights; load units squared per Hz)."""
    psd = {ld: np.mean([band_psd(r[ld], dt, SPECTRUM_HZ) for r, dt in zip(residuals, dts)],
                       axis=0).tolist() for ld in loads}
    size = {ld: float(np.sqrt(np.mean(np.concatenate([r[ld] for r in residuals]) ** 2)))
            for ld in loads}
    return {"rms": size, "bands_hz": [list(b) for b in SPECTRUM_HZ], "psd": psd}


def whitens(before: float, after: float) -> bool:
    """Does an explanation that turns a residual of redness `before` into one of `after`
    explain structure rather than track a disturbance? Yes when what it leaves is white
    (`after < RED_MIN`), or when it cuts the redness by the same factor at least (a
    deterministic effect, once fitted, takes the low-frequency power it put there; a proxy
    of a disturbance, a function of the states the disturbance drove, leaves the residual
    about as red as before). The adequacy test of every explanation built on the states'
    dynamics: a probe, or a catalogue entry that filters the states (`Effect.filters_states`);
    a disturbance drives the states, so only those can track one."""
    return after < RED_MIN or after * RED_MIN <= before
