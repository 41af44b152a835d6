"""Writing reconstructed flights: `DIR/NAME.csv` (section 1), `DIR/vehicle.json` and
`DIR/reconstruction.json`, each atomically (a temporary file renamed), so that nothing already
written is lost when something fails."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from .._errors import InputError
from ..data._sidefiles import VEHICLE_FILE
from ._workers import run_all

REPORT = "reconstruction.json"


def _atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _clean(x):
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_clean(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def flight_csv(columns: dict[str, np.ndarray]) -> str:
    """The CSV text of a flight's columns (header row, 12 significant digits)."""
    data = np.column_stack([np.asarray(v, float) for v in columns.values()])
    row = ",".join(["%.12g"] * data.shape[1]) + "\n"  # one format of every row, in C
    return ",".join(columns) + "\n" + (row * data.shape[0]) % tuple(data.ravel().tolist())


def write_flight(out_dir, flight) -> Path:
    """Write one `ReconstructedFlight` as `out_dir/NAME.csv`."""
    path = Path(out_dir) / f"{flight.name}.csv"
    _atomic(path, flight_csv(flight.columns))
    return path


def write_reconstruction(result, out_dir, *, pool=None) -> list[Path]:
    """Write the flights, `vehicle.json` and `reconstruction.json` of a reconstruction.

    Each file is written atomically into `out_dir`; the flights' `vehicle.json` must agree,
    and no two flights of different takes may share a name (refused before anything is written);
    entries already in an existing `reconstruction.json` for other flights are kept.

    **Arguments:**
    - `result`: what [`fwid.reconstruct`][] returned;
    - `out_dir`: the folder (created if needed);
    - `pool`: worker processes that write the flights (`fwid.reconstruction._workers.start`),
      or None: here.

    **Returns:** the paths written.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a folder; give --out a folder")
    written = []
    vehicles = {json.dumps(fl.vehicle, sort_keys=True) for fl in result.flights}
    if len(vehicles) > 1:
        raise InputError(f"the takes have different vehicle.json files; reconstruct them into "
                         f"separate --out folders ({', '.join(fl.vehicle_path for fl in result.flights)})")
    names = [fl.name for fl in result.flights]  # a take's own flights never share one
    for name in {n for n in names if names.count(n) > 1}:
        raise InputError(f"two takes give the flight {name} "
                         f"({'; '.join(fl.entry['source'] for fl in result.flights if fl.name == name)})"
                         "; write them into separate folders, or rename one take")
    out.mkdir(parents=True, exist_ok=True)
    written += run_all(write_flight, [((out, fl), {}) for fl in result.flights], pool)
    if result.flights:
        v = out / VEHICLE_FILE
        _atomic(v, json.dumps(result.flights[0].vehicle, indent=2) + "\n")
        written.append(v)
    report = out / REPORT
    old = []
    if report.is_file():
        try:
            old = json.loads(report.read_text()).get("flights", [])
        except (json.JSONDecodeError, AttributeError):
            old = []
    new = [fl.entry for fl in result.flights]
    names = {e["flight"] for e in new}
    entries = [e for e in old if isinstance(e, dict) and e.get("flight") not in names] + new
    _atomic(report, json.dumps(_clean({"flights": entries}), indent=2) + "\n")
    written.append(report)
    return written
