"""The shrink on the test flights alone: its p value, the smallest shrink these flights
resolve, and how many test flights would settle it.

The selection's evidence (`_significance.py`) is a cross-fit over every flight, training and
test alike: the test flights are fitted in one half and scored in the other, so they are not
unseen by the selection (with one flight each way, swapping training and test leaves most
of its p values as they were). The shrink (`shrink_pct`) is different: the baseline and
the effect are re-fitted on the training flights only and scored on the test flights. Its
own test is the same one-sided t test, on the test flights' blocks of about `BLOCK_S` seconds:

    d_j = log( sum_l SSE_j,l(before) / s_l  /  sum_l SSE_j,l(after) / s_l ),

over the effect's affected loads, all frequencies, each load scaled by its held-out mean
square before (`s_l`), as the shrink is. The smallest overall shrink the blocks resolve is the
detection limit of that test (`Evidence.detection_limit`: probability `POWER` at the level),
converted from the drop of the mean square to the drop of the RMS. A shrink below it is
within the noise of these flights. The limit falls like `1 / sqrt(blocks)`, so, with test
flights of the same length and kind, `ceil(n_test (d_limit / mean d)^2)` test flights would
bring it down to the shrink observed (`flights_to_settle`; `None` when the shrink is not
positive: more flights would not make it one).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ._significance import Evidence, block_count


def heldout_test(before: Sequence[dict], after: Sequence[dict], sigs, loads: Sequence[str],
                 scale: dict, shrink_pct: float, level: float, flights: Sequence[str]) -> dict:
    """The `heldout` entry of a candidate's row: the test of its shrink on the test flights.

    **Arguments:** `before`, `after` (per test flight, by load: the residuals of the
    baseline and of the model with the effect, both fitted on the training flights), `sigs`
    (the test flights' signals, for the blocks), `loads` (the affected loads), `scale` (per
    load, its held-out RMS before), `shrink_pct` (the observed overall shrink), `level` (of
    the test), `flights` (the test flights' names).

    **Returns:** `{"flights", "blocks", "p", "detection_limit_pct" (the smallest RMS shrink
    these blocks resolve), "within_noise", "flights_to_settle"}`.
    """
    d = []
    for b, a, s in zip(before, after, sigs):
        count = block_count(s)
        for k in range(count):
            lo, hi = s.block_rows(k, count)
            eb = sum(float(np.sum(b[ld][lo:hi] ** 2)) / scale[ld] ** 2 for ld in loads
                     if scale[ld] > 0)
            ea = sum(float(np.sum(a[ld][lo:hi] ** 2)) / scale[ld] ** 2 for ld in loads
                     if scale[ld] > 0)
            d.append(math.log(max(eb, 1e-300) / max(ea, 1e-300)))
    ev = Evidence("", (), np.asarray(d), {}, {})
    limit = 1.0 - math.sqrt(max(0.0, 1.0 - ev.detection_limit(level)))
    within = bool(shrink_pct < 100.0 * limit)
    dmin = -2.0 * math.log(max(1.0 - limit, 1e-300))  # the limit as a mean log ratio
    settle = (math.ceil(len(flights) * (dmin / ev.mean) ** 2) if within and ev.mean > 0
              and shrink_pct > 0 and math.isfinite(dmin) else None)
    return {"flights": list(flights), "blocks": ev.n, "p": ev.p,
            "detection_limit_pct": 100.0 * limit, "within_noise": within,
            "flights_to_settle": settle}
