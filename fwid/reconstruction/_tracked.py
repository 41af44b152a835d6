"""A tracked rigid body's pose (any vendor's export, already in north-east-down) made a
`RawTake`: signs of the quaternion made continuous, glitches dropped (`_glitches`), the
untracked ends cut, the dropouts checked, and the autopilot's log beside the take read
(`_onboard`), where there is one."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import FlightDataError
from ._glitches import drop_glitches
from ._onboard import read_onboard
from ._raw import RawTake, dropouts, take_name, trim_untracked
from ._rotations import continuous_sign, matrix_to_quat


def pose_take(path: str, t, pos, R, tracked, frame: str, warnings: list[str], onboard,
              max_dropout: float, source: str, what: str, controls=None) -> RawTake:
    """The `RawTake` of a body's pose `pos` `(n, 3)` (m) and body -> world matrices `R`
    `(n, 3, 3)`, both in north-east-down, on the uniform time base `t`; NaN / anything where
    `tracked` is False.

    **Arguments:**
    - `frame`: the take's world frame as recorded (for the record);
    - `warnings`: what the reader has said so far;
    - `onboard`: the autopilot's log (default `NAME.onboard.csv` beside the take: a take
      without one is the pose alone), `False`: read none;
    - `source`: the form, said in `reconstruction.json`; `what`: the body, for messages;
    - `controls`: columns on `t` found in the take itself (a flapping frequency), or None.
    """
    if not np.any(tracked):
        raise FlightDataError(f"{path}: {what} is never tracked in the take (every pose cell is "
                              "empty); pick a body that was tracked, or fill the take in the "
                              "tracking software before exporting it")
    warnings = list(warnings)
    q = continuous_sign(np.where(tracked[:, None], matrix_to_quat(R), np.nan), tracked)
    kept, said = drop_glitches(t, q, tracked, pos, path)
    warnings += said
    cut = trim_untracked(t, pos, q, kept, {"dropped": tracked & ~kept}, controls)
    if cut is None:
        raise FlightDataError(f"{path}: {what} is tracked on fewer than 3 rows")
    t, pos, q, tracked, extra, controls = cut
    gaps = dropouts(t, tracked, path, max_dropout, extra["dropped"])
    name = take_name(path)
    if onboard is False:
        log = None
    else:
        log = read_onboard(onboard or Path(path).with_name(f"{name}.onboard.csv"), path,
                           given=onboard is not None)
        if log is None:
            warnings.append(f"no autopilot log ({name}.onboard.csv) beside the take: the pose "
                            "alone, no controls")
    return RawTake(name, path, source, frame, t, pos, q, tracked, controls, log, gaps, warnings)
