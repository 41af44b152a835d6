"""Where the states came from: `reconstruction.json` (the raw-recording formats) beside the flights.

A `random-disturbance` verdict says the held-out load residual is red and nothing measured
predicts it. With states from the user's own filter, that is either a disturbance the vehicle
felt (process noise, gusts) or coloured errors in the states (a filter's lag, a gyro bias
walk, smoothed velocities): both are stationary red noise in the residual, and the flights
alone cannot tell them apart. States that `fwid reconstruct` rebuilt from the raw recordings
carry no filter of the user's, and its `reconstruction.json` says how consistent each flight
was (clock offset, tracking dropouts, warnings, and any further quality figures it records);
the diagnosis reports them beside the verdict, keeping only the keys that are there.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from .._errors import InputError
from .._words import count

#: The file `fwid reconstruct` writes beside the flights it rebuilds.
FILE = "reconstruction.json"


def _entries(folder: Path, cache: dict) -> dict[str, dict]:
    """The entries of `folder`'s `reconstruction.json` by flight file name (`{}`: no file)."""
    if folder in cache:
        return cache[folder]
    f = folder / FILE
    out: dict[str, dict] = {}
    if f.is_file():
        try:
            doc = json.loads(f.read_text())
        except (OSError, ValueError) as exc:
            raise InputError(f"{f}: not readable as JSON ({exc}); re-run fwid reconstruct "
                             "or remove the file") from None
        flights = doc.get("flights") if isinstance(doc, dict) else None
        if not isinstance(flights, list) or not all(
                isinstance(e, dict) and isinstance(e.get("flight"), str) for e in flights):
            raise InputError(f"{f}: expected {{\"flights\": [{{\"flight\": \"NAME.csv\", "
                             "...}]} (see the guide's 'Formats and interfaces' page, "
                             "docs/reference/formats.md); re-run fwid reconstruct or remove "
                             "the file")
        out = {Path(e["flight"]).name: e for e in flights}
    cache[folder] = out
    return out


def read_reconstruction(files: Sequence[str | Path]) -> list[dict | None]:
    """Each flight file's entry in the `reconstruction.json` beside it.

    **Arguments:** `files` (the flights' CSV files, in the order of the flights diagnosed).

    **Returns:** per file, its entry, or `None` (no `reconstruction.json` in its folder, or
    none naming it).

    **Raises:** `InputError` when a `reconstruction.json` is not a JSON object with a list
    `flights` of objects each naming its `flight`.
    """
    cache: dict = {}
    return [_entries(Path(f).parent, cache).get(Path(f).name) for f in files]


def _dropout_s(dropouts) -> float | None:
    try:
        return float(sum(float(b) - float(a) for a, b in dropouts))
    except (TypeError, ValueError):
        return None


def provenance(names: Sequence[str], entries: Sequence[dict | None] | None) -> dict:
    """`diagnosis.json`'s `states` block: whether the flights' states were reconstructed by
    `fwid reconstruct` and, per flight so reconstructed, what its `reconstruction.json` entry
    says (the keys that are there: `source`, `clock_offset_s`, the dropouts' count and total
    length, `warnings`, and every further key as recorded).

    **Arguments:** `names` (the diagnosed flights' names), `entries` (per flight, its entry
    as `read_reconstruction` returns them, or `None`: not looked for).

    **Returns:** `{"reconstructed": "all" | "some" | "none", "flights": [...], "missing": [names
    without an entry]}`.
    """
    entries = list(entries) if entries is not None else [None] * len(names)
    if len(entries) != len(names):
        raise InputError(f"reconstruction: {len(entries)} entries for {len(names)} flights; "
                         "pass one entry (or None) per training and test flight, in order")
    rows, missing = [], []
    for n, e in zip(names, entries):
        if e is None:
            missing.append(n)
            continue
        row = {"flight": n}
        for k, v in e.items():
            if k == "flight":
                continue
            if k == "dropouts" and isinstance(v, list):
                row["dropouts"] = len(v)
                total = _dropout_s(v)
                if total is not None:
                    row["dropout_s"] = total
            else:
                row[k] = v
        rows.append(row)
    state = "all" if not missing else "some" if rows else "none"
    return {"reconstructed": state, "flights": rows, "missing": missing}


def provenance_text(block: dict | None) -> str | None:
    """The `states` block in one line (`None` when no flight was reconstructed)."""
    if not block or not block["flights"]:
        return None
    rows = block["flights"]
    parts = [f"{len(rows)} of {len(rows) + len(block['missing'])} flights rebuilt from raw "
             "recordings by fwid reconstruct"]
    offsets = [r["clock_offset_s"] for r in rows if isinstance(r.get("clock_offset_s"),
                                                                 (int, float))]
    if offsets:
        lo, hi = f"{min(offsets):.3f}", f"{max(offsets):.3f}"
        parts.append(f"clock offset {lo} s" if lo == hi else f"clock offsets {lo} to {hi} s")
    drop = [r for r in rows if r.get("dropouts")]
    if any("dropouts" in r for r in rows):
        total = sum(r.get("dropout_s", 0.0) for r in drop)
        parts.append(f"tracking dropouts in {count(len(drop), 'flight')} ({total:.2f} s in all)")
    warned = [r["flight"] for r in rows if r.get("warnings")]
    if any("warnings" in r for r in rows):
        parts.append(f"warnings on {', '.join(warned)}" if warned else "no warnings")
    standard = {"flight", "source", "clock_offset_s", "dropouts", "dropout_s", "warnings"}
    extra = sorted({k for r in rows for k, v in r.items()
                    if k not in standard and isinstance(v, (int, float))})
    words = {"duration_s": ("{} s long", "{} to {} s long"), "rate_hz": ("at {} Hz", "at {} to {} Hz")}
    for k in extra:
        vals = [r[k] for r in rows if isinstance(r.get(k), (int, float))]
        lo, hi = f"{min(vals):.3g}", f"{max(vals):.3g}"
        one, two = words.get(k, (f"{k} {{}}", f"{k} {{}} to {{}}"))
        parts.append(one.format(lo) if lo == hi else two.format(lo, hi))
    return "; ".join(parts)
