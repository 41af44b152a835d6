"""How strong an injected effect is against the noise on its loads: the yardstick of
"strength 1" (`_effects`)."""

from __future__ import annotations

import numpy as np
from scipy import signal

from ._delfly import DELFLY, FORCES, DelFly
from ._effects import Effect, form_axes
from ._reconstruct import LOAD_CUTOFF, reconstruct_loads
from ._simulate import simulate_flight

#: The band split [Hz] of the yardstick: cycle-averaged below, flapping above (the paper's
#: Sec. III.B split, as `fwid.diagnose` uses).
SPLIT = 5.0
BANDS = ("slow", "fast")


def _bands(x, rate):
    """`{"slow": below SPLIT, "fast": the rest}` of `x` minus its mean (zero-phase,
    4th-order Butterworth)."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    slow = signal.sosfiltfilt(signal.butter(4, SPLIT, fs=rate, output="sos"), x)
    return {"slow": slow, "fast": x - slow}


def effect_noise_ratio(
    effect: str | tuple = "flap-coupling",
    form: str | tuple | None = None,
    strength: float | tuple = 1.0,
    axes: tuple[str, ...] | None = None,
    *,
    seed: int = 0,
    vehicle: DelFly = DELFLY,
    noise: float = 1.0,
    **kw,
) -> dict:
    """The effect's load RMS over the sensor-noise RMS of the reconstructed loads, per load
    and band, during a default manoeuvre (`simulate_flight` defaults: 3211, 4.5 s, 200 Hz;
    `kw` may change them) on each axis in `axes` (default: the axes whose flights show it).

    - effect: `meta["loads_effect"]` (true loads minus the paper's model, Eqs. 1-6 + 12, at
      the true states and the measured input);
    - noise: the reconstructed loads of the noisy flight minus those reconstructed, with the
      same filter, from its noise-free states;
    - both split at `SPLIT` (5 Hz) into the cycle-averaged (`slow`) and flapping (`fast`)
      band: the ratio is taken in each band, because the noise of differentiated states
      grows with frequency and would otherwise swamp any cycle-averaged effect.

    **Returns:** `{axis: {"ratio": {band: {load: r}}, "effect_rms": .., "noise_rms": ..
    (same shape), "max": largest r, "load": its load, "band": its band}, "max": largest r
    over the axes}`. Strength 1 of every form is sized so that `max` is about 1 to 1.5 on
    the axes that show it, like the original forms (table in `benchmarks/README.md`).
    """
    eff = Effect(effect, strength, form)
    if axes is None:
        axes = tuple(a for a in ("lon", "lat")
                     if any(a in form_axes(n, f) for n, f, _ in eff.parts))
    out: dict = {}
    for axis in axes:
        fl = simulate_flight(axis=axis, seed=seed, effect=eff, vehicle=vehicle, noise=noise, **kw)
        meta = fl["meta"]
        rate = 1.0 / (fl["t"][1] - fl["t"][0])
        clean = reconstruct_loads(meta["clean"], rate, meta["trim"], vehicle,
                                  kw.get("load_cutoff", LOAD_CUTOFF))
        e = {b: {} for b in BANDS}
        n = {b: {} for b in BANDS}
        for k in FORCES:
            eb, nb = _bands(meta["loads_effect"][k], rate), _bands(fl[k] - clean[k], rate)
            for b in BANDS:
                e[b][k], n[b][k] = float(np.std(eb[b])), float(np.std(nb[b]))
        r = {b: {k: e[b][k] / n[b][k] if n[b][k] > 0 else float("inf") for k in FORCES}
             for b in BANDS}
        band, top = max(((b, k) for b in BANDS for k in FORCES), key=lambda bk: r[bk[0]][bk[1]])
        out[axis] = {"effect_rms": e, "noise_rms": n, "ratio": r, "max": r[band][top],
                     "load": top, "band": band}
    out["max"] = max(out[a]["max"] for a in axes)
    return out
