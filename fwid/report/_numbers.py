"""Numbers printed in a bounded width: tables and figure labels stay readable whatever a fit
gave (an R2 of -2.5e7 from a diverged simulation, an RMS of 1e126, NaN).

[`fixed`][] writes a number in fixed point when it fits its width and in scientific notation
when it does not; [`score`][] writes a score bounded above by 1 (R2, a correlation), a large
negative one as `<-1e3` (such a fit explains nothing; the exact value carries no more
information).
"""

from __future__ import annotations

import math

#: Scores below this print as `<-1e3`.
SCORE_FLOOR = -1e3


def fixed(x, width: int, decimals: int = 2) -> str:
    """`x` right-aligned in `width` characters, at least one of them a space (a column never
    runs into the one before it; any number fits from `width` 8 on): fixed point with `decimals` when it fits, else scientific
    notation with as many digits as fit, `nan`/`inf` as such, `-` for `None`."""
    room = max(width - 1, 6)
    if x is None:
        return f"{'-':>{width}}"
    x = float(x)
    if not math.isfinite(x):
        return f"{('nan' if math.isnan(x) else ('inf' if x > 0 else '-inf')):>{width}}"
    text = f"{x:.{decimals}f}"
    if len(text) > room:
        for digits in range(max(decimals, 2), -1, -1):
            text = f"{x:.{digits}e}"
            if len(text) <= room:
                break
    return f"{text:>{width}}"


def score(x, width: int, decimals: int = 2) -> str:
    """A score at most 1 (R2, a correlation), right-aligned in `width`: `<-1e3` below
    [`SCORE_FLOOR`][], else as [`fixed`][]."""
    if x is not None and math.isfinite(float(x)) and float(x) < SCORE_FLOOR:
        return f"{'<-1e3':>{width}}"
    return fixed(x, width, decimals)


def compact(x, decimals: int = 2) -> str:
    """A score for a label (no padding), as [`score`][]."""
    return score(x, 10, decimals).strip()
