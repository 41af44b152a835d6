"""The autopilot's log beside a tracking take (`NAME.onboard.csv`): its own clock `t` and
the controls and gyro `de dr f p q r` (+ extra columns)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import FlightDataError
from ._raw import OnboardLog, check_time, parse_rows, read_lines

LOG_COLUMNS = ("t", "de", "dr", "f", "p", "q", "r")


def read_onboard(path, take: str, given: bool = False) -> OnboardLog | None:
    """The autopilot's log `t,de,dr,f,p,q,r` (+ extras) of a take, or None when there is
    none beside the take (a tracking-only take); a log named with `given` that is not
    there, a missing column or a non-uniform clock is a `FlightDataError` naming the
    file."""
    path = Path(path)
    if not path.is_file():
        if given:
            raise FlightDataError(f"{take}: no such autopilot log {path} (--onboard); give the "
                                  "path of the take's log, or leave --onboard out for the pose "
                                  "alone")
        return None
    lines = read_lines(path)
    if not lines:
        raise FlightDataError(f"{path}: empty autopilot log")
    header = [h.strip() for h in lines[0].split(",")]
    missing = [c for c in LOG_COLUMNS if c not in header]
    if missing:
        raise FlightDataError(f"{path}: the autopilot log lacks column(s) {', '.join(missing)}; "
                              f"it needs {','.join(LOG_COLUMNS)}")
    data = parse_rows(lines[1:], str(path), 2, width=len(header))
    cols = {h: data[:, i] for i, h in enumerate(header) if h}
    check_time(cols["t"], str(path), 2)
    for c in LOG_COLUMNS[1:]:
        bad = np.flatnonzero(~np.isfinite(cols[c]))
        if bad.size:
            raise FlightDataError(f"{path}, line {bad[0] + 2}: column {c} is empty; the log "
                                  "needs every cell")
    return OnboardLog(str(path), cols.pop("t"), cols)


