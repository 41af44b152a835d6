"""Where the gap lies: the baseline's held-out load error by output, band, time and state."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, Signals

#: Half-width [Hz] of a harmonic's own band, before the spread of the flapping frequency.
HARMONIC_HALF_WIDTH = 0.6
#: Sidebands reach this far [Hz] from each harmonic (the manoeuvre band, below the split).
SIDEBAND_REACH = 5.0
#: Split between the cycle-averaged band and the rest [Hz] (Section III.B).
SPLIT = 5.0
#: Window after an input event [s] for the input-aligned error.
AFTER_INPUT = 1.0
#: Quantile bins over a state.
STATE_BINS = 4
BAND_NAMES = ("averaged",) + tuple(f"harmonic_{n}" for n in (1, 2, 3)) + tuple(
    f"sidebands_{n}" for n in (1, 2, 3)) + ("rest",)


def band_of(freq: np.ndarray, f_mean: float, f_spread: float) -> np.ndarray:
    """Index into `BAND_NAMES` of each frequency [Hz]."""
    out = np.full(freq.shape, len(BAND_NAMES) - 1)
    for n in (3, 2, 1):
        dist = np.abs(freq - n * f_mean)
        half = HARMONIC_HALF_WIDTH + 0.5 * n * f_spread
        out[dist <= SIDEBAND_REACH] = 3 + n
        out[dist <= half] = n
    out[freq <= SPLIT] = 0
    return out


def band_energy(r: np.ndarray, s: Signals) -> np.ndarray:
    """Energy of `r` in each of `BAND_NAMES` (Parseval on the record, mean removed)."""
    spec = np.abs(np.fft.rfft(r - np.mean(r))) ** 2
    spec[1:] *= 2.0
    freq = np.fft.rfftfreq(len(r), s.dt)
    idx = band_of(freq, s.f_mean, s.f_spread)
    return np.bincount(idx, weights=spec, minlength=len(BAND_NAMES)) / len(r) ** 2


def input_events(s: Signals, axis: str) -> np.ndarray:
    """Samples within `AFTER_INPUT` s after the control moved fast (its rate above a third of
    its largest)."""
    d = s.slow.get(AXIS_INPUT[axis])
    if d is None:
        return np.zeros(s.n, bool)
    rate = np.abs(np.gradient(d, s.dt))
    moving = rate > max(rate.max() / 3.0, 1e-12)
    window = round(AFTER_INPUT / s.dt)
    out = np.zeros(s.n, bool)
    for i in np.flatnonzero(moving):
        out[i : i + window] = True
    return out


def _pct(a, b):
    return float(100.0 * a / b) if b > 0 else 0.0


def rms(x) -> float:
    """Root mean square (NaN for no samples)."""
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")


def gap_map(
    sigs: Sequence[Signals],
    residuals: Sequence[Mapping[str, np.ndarray]],
    measured: Sequence[Mapping[str, np.ndarray]],
    axis: str,
) -> dict:
    """The gap map of the diagnosis report's `localisation` from held-out residuals (full band, by load).

    - `by_output[load]`: `rms`, `unexplained_pct` (residual variance over the measured
      variance, i.e. 1 - R^2), and `share_pct` (its share of the sum over the axis's loads; 0
      for a load of the other axis, marked `other_axis`: with that axis quiet it is about all
      noise, and would crowd out the axis's own gap).
    - `by_band[load]`: per cent of the residual energy in each of `BAND_NAMES`.
    - `by_time[load]`: RMS in the steady start and in the manoeuvre, in the `AFTER_INPUT`
      window after input events and elsewhere, and per flap cycle (median, 90th percentile,
      largest and where).
    - `by_state[load]`: mean-square residual in `STATE_BINS` quantile bins of each
      cycle-averaged state and control, relative to its mean; `top` names the state of the
      manoeuvred axis (or its control) whose bins differ most.
    """
    loads = list(residuals[0])
    states = AXIS_STATES["lon"] + AXIS_STATES["lat"] + ("de", "dr")
    out = {"by_output": {}, "by_band": {}, "by_time": {}, "by_state": {}}
    unexplained = {}
    for ld in loads:
        r = [res[ld] for res in residuals]
        m = [meas[ld] for meas in measured]
        var_r = np.mean(np.concatenate([x - x.mean() for x in r]) ** 2)
        var_m = np.mean(np.concatenate([x - x.mean() for x in m]) ** 2)
        unexplained[ld] = var_r / var_m if var_m > 0 else 0.0
        out["by_output"][ld] = {"rms": rms(np.concatenate(r)),
                                "unexplained_pct": 100.0 * unexplained[ld]}
        energy = sum(band_energy(x, s) * len(x) for x, s in zip(r, sigs))
        out["by_band"][ld] = {b: _pct(e, energy.sum()) for b, e in zip(BAND_NAMES, energy)}
        out["by_time"][ld] = _by_time(sigs, r, axis)
        out["by_state"][ld] = _by_state(sigs, r, states, AXIS_STATES[axis] + (AXIS_INPUT[axis],))
    own = [ld for ld in loads if ld in AXIS_LOADS[axis]] or loads
    total = sum(unexplained[ld] for ld in own)
    for ld in loads:
        out["by_output"][ld]["share_pct"] = _pct(unexplained[ld], total) if ld in own else 0.0
        if ld not in own:
            out["by_output"][ld]["other_axis"] = True
    return out


def _by_time(sigs, r, axis) -> dict:
    steady = np.concatenate([x[~s.manoeuvre] for x, s in zip(r, sigs)])
    man = np.concatenate([x[s.manoeuvre] for x, s in zip(r, sigs)])
    ev = [input_events(s, axis) for s in sigs]
    after = np.concatenate([x[e] for x, e in zip(r, ev)])
    rest = np.concatenate([x[~e] for x, e in zip(r, ev)])
    cycles = []
    for x, s in zip(r, sigs):
        k = np.floor((s.phase - s.phase[0]) / (2 * np.pi)).astype(int)
        for c in np.unique(k):
            sel = k == c
            if sel.sum() >= 3:
                cycles.append((rms(x[sel]), s.name, float(s.t[sel][0])))
    vals = np.array([c[0] for c in cycles])
    worst = cycles[int(np.argmax(vals))]
    return {
        "steady_rms": rms(steady),
        "manoeuvre_rms": rms(man),
        "manoeuvre_to_steady": rms(man) / rms(steady) if len(steady) else float("nan"),
        "after_input_rms": rms(after),
        "elsewhere_rms": rms(rest),
        "per_cycle": {"median": float(np.median(vals)), "p90": float(np.percentile(vals, 90)),
                      "max": worst[0], "max_flight": worst[1], "max_t": worst[2]},
    }


def _by_state(sigs, r, states, manoeuvred) -> dict:
    """Bins of every state in `states`; `top` among the `manoeuvred` axis's states and control
    (the quiet axis's barely move: their bins split noise)."""
    r2 = np.concatenate(r) ** 2
    mean = float(np.mean(r2))
    bins, spread = {}, {}
    for st in states:
        if not all(st in s.slow for s in sigs):
            continue
        x = np.concatenate([s.slow[st] for s in sigs])
        if np.ptp(x) <= 0:
            continue
        edges = np.quantile(x, np.linspace(0, 1, STATE_BINS + 1))
        idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, STATE_BINS - 1)
        rel = [float(np.mean(r2[idx == b]) / mean) if np.any(idx == b) else float("nan")
               for b in range(STATE_BINS)]
        bins[st] = {"edges": [float(e) for e in edges], "relative_ms": rel}
        spread[st] = np.nanmax(rel) / max(np.nanmin(rel), 1e-12)
    ranked = {st: v for st, v in spread.items() if st in manoeuvred}
    top = max(ranked, key=ranked.get) if ranked else None
    return {"top": top, "top_spread": float(spread[top]) if top else None, "bins": bins}
