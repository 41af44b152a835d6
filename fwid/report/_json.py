"""Machine-readable reports (the report format), written whole or not at all."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from ._bounded import identifiable


def _clean(obj):
    """JSON-safe: numpy scalars/arrays to Python, NaN/inf to None."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray) or hasattr(obj, "__jax_array__") or type(obj).__module__.startswith("jax"):
        return _clean(np.asarray(obj).tolist())
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        return x if math.isfinite(x) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def _default_mode() -> int:
    """The mode a file created by `open()` gets: 0666 less the process's umask (0644 for the
    usual umask 022)."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def write_text(path: str | Path, text: str) -> Path:
    """Write `text` atomically: to a temporary file beside `path`, then renamed (whole or
    not at all), with the permissions of any file the user writes (not the temporary
    file's 0600)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.chmod(tmp, _default_mode())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def write_json(path: str | Path, obj) -> Path:
    """Write `obj` as JSON atomically: a failed write leaves an earlier file untouched.

    numpy and JAX values become numbers and lists; NaN and infinities become `null`.

    **Arguments:**

    - `path`: the file to write.
    - `obj`: a JSON-able value (dicts, lists, numbers, strings, numpy and JAX arrays).

    **Returns:** the path written.
    """
    return write_text(path, json.dumps(_clean(obj), indent=2, allow_nan=False) + "\n")


def parameters_csv(parameters: dict) -> str:
    """The `parameters.csv` beside `report.json`: one row per parameter with `value`, `std`
    (Cramer-Rao corrected for coloured residuals, or the spread over flights), `std_cr`
    (plain Cramer-Rao), `rel_std_pct` (`100 |std / value|`) and `identifiable` (`true`,
    `false` when the std exceeds the value a thousandfold or is not finite:
    `fwid.report._bounded.identifiable`); empty where not known, and the three spreads empty
    where the parameter is not identifiable (`report.json` keeps them)."""

    def cell(x):
        return "" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.10g}"

    rows = ["name,value,std,std_cr,rel_std_pct,identifiable"]
    for name, p in parameters.items():
        v, sd = p.get("value"), p.get("std")
        rel = 100.0 * abs(sd / v) if (v not in (None, 0) and sd is not None) else None
        ok = identifiable(v, sd)
        spreads = [sd, p.get("std_cr"), rel] if ok is not False else [None] * 3
        rows.append(",".join([name, cell(v), *map(cell, spreads),
                              "" if ok is None else str(ok).lower()]))
    return "\n".join(rows) + "\n"
