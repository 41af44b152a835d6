"""Fit metrics per output (the paper's Tables 2, 5 and 8)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from jaxtyping import Array, Float


def fit_metrics(
    z: Float[Array, "n ny"], y: Float[Array, "n ny"], names: Sequence[str]
) -> dict[str, dict[str, float]]:
    """Output correlation, R^2, RMS and RMS as % of the measured range, per output (Tables 2, 5, 8).

    - `corr`: Pearson correlation of measured and model output.
    - `r2`: `1 - sum (z - y)^2 / sum (z - mean z)^2` (can be negative on validation data).
    - `rms`: root mean square of `z - y`, in the output's unit.
    - `rms_pct`: `100 rms / (max z - min z)`.

    **Arguments:**

    - `z`: the measured outputs, shape `(n, ny)`.
    - `y`: the model's outputs, shape `(n, ny)`.
    - `names`: the outputs' names, `ny` of them.

    **Returns:** `{name: {"corr", "r2", "rms", "rms_pct"}}`.
    """
    z = np.asarray(z, dtype=float)
    y = np.asarray(y, dtype=float)
    out = {}
    for j, name in enumerate(names):
        zj, yj = z[:, j], y[:, j]
        e = zj - yj
        sst = np.sum((zj - zj.mean()) ** 2)
        rng = np.ptp(zj)
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = (float(np.corrcoef(zj, yj)[0, 1]) if np.ptp(yj) > 0 and np.ptp(zj) > 0
                    else float("nan"))
        rms = float(np.sqrt(np.mean(e**2)))
        out[name] = dict(
            corr=corr,
            r2=float(1.0 - np.sum(e**2) / sst) if sst > 0 else float("nan"),
            rms=rms,
            rms_pct=float(100.0 * rms / rng) if rng > 0 else float("nan"),
        )
    return out
