"""Reading a flight's CSV file into numpy columns (no JAX): the header, the numbers, and
each sample's line in the file for the messages of `fwid.data._checks`."""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from .._errors import FlightDataError
from ._checks import KNOWN_COLUMNS


def _split_header(line: str) -> list[str]:
    line = line.strip()
    if line.startswith("#"):
        line = line[1:]
    return [f.strip().strip('"').strip("'").strip() for f in line.split(",")]


def _is_float(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def read_csv(
    path: Path, name: str, require: tuple[str, ...] = ()
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """All numeric columns of the CSV by name (`t` included), in file order, and each
    sample's line in the file (1-based, the header counted: as an editor shows it).

    Columns named in the flight-data format or in `require` must be fully numeric (an empty
    cell reads as NaN, caught later); an extra column with non-numeric cells is dropped.
    """
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise FlightDataError(f"{name}: cannot read the file ({e.strerror or e})") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise FlightDataError(
            f"{name}: not a text file (cannot decode as UTF-8); save the flight as a CSV "
            "text file"
        ) from None
    lines = text.splitlines()
    # The header: the first non-blank line, skipping leading '#' comments without commas.
    h = next(
        (
            i
            for i, ln in enumerate(lines)
            if ln.strip() and not (ln.lstrip().startswith("#") and "," not in ln)
        ),
        None,
    )
    if h is None:
        raise FlightDataError(f"{name}: file is empty; expected a header row and data rows")
    header = _split_header(lines[h])
    if len(header) == 1:
        for sep, word in ((";", "semicolons"), ("\t", "tabs")):
            if sep in lines[h]:
                raise FlightDataError(
                    f"{name}: columns are separated by {word}, not commas; save the file as "
                    "comma-separated values"
                )
    if all(_is_float(f) for f in header if f):
        raise FlightDataError(
            f"{name}: line {h + 1} has no column names; add a header row such as "
            "'t,q,u,w,theta,de'"
        )
    seen: dict[str, int] = {}
    for j, col in enumerate(header):
        if not col:
            continue  # unnamed (e.g. a trailing comma): ignored
        if col in seen:
            raise FlightDataError(
                f"{name}: column '{col}' appears twice in the header (columns {seen[col] + 1} "
                f"and {j + 1}); rename or remove one"
            )
        seen[col] = j
    names = list(seen)
    usecols = [seen[c] for c in names]
    strict = set(KNOWN_COLUMNS) | set(require)

    data_lines = lines[h + 1 :]
    commas = len(header) - 1
    ragged = any(
        ln.count(",") != commas and ln.strip() and not ln.lstrip().startswith("#")
        for ln in data_lines
    )
    if ragged:  # rows with more or fewer fields than the header: find and name them
        return _read_csv_slow(name, header, names, seen, data_lines, h + 2, strict)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            arr = np.loadtxt(
                io.StringIO("\n".join(data_lines)),
                delimiter=",",
                comments="#",
                usecols=usecols,
                ndmin=2,
                dtype=float,
            )
    except ValueError:
        return _read_csv_slow(name, header, names, seen, data_lines, h + 2, strict)
    if arr.shape[0] == 0:
        raise FlightDataError(f"{name}: no data rows under the header; the file holds no samples")
    lines_of = np.arange(arr.shape[0]) + h + 2  # no blank or comment line among the rows
    if len(data_lines) != arr.shape[0]:
        kept = [h + 2 + k for k, ln in enumerate(data_lines) if ln.split("#", 1)[0].strip()]
        if len(kept) == arr.shape[0]:
            lines_of = np.array(kept)
    return {c: arr[:, k] for k, c in enumerate(names)}, lines_of


def _read_csv_slow(name, header, names, seen, data_lines, first_line_no, strict):
    """Cell-by-cell parse of a file numpy could not read: finds the bad cell."""
    rows: list[list[str]] = []
    line_nos: list[int] = []
    nf = len(header)
    for k, ln in enumerate(data_lines):
        s = ln.strip()
        if not s or s.startswith("#"):
            continue
        fields = ln.split(",")
        if len(fields) != nf:
            if len(fields) > nf and not any(f.strip() for f in fields[nf:]):
                fields = fields[:nf]
            else:
                raise FlightDataError(
                    f"{name}: line {first_line_no + k} has {len(fields)} fields but the header "
                    f"has {nf}; fix the row or remove it"
                )
        rows.append(fields)
        line_nos.append(first_line_no + k)
    if not rows:
        raise FlightDataError(f"{name}: no data rows under the header; the file holds no samples")
    out = {}
    for col in names:
        j = seen[col]
        cells = [r[j].strip().strip('"') for r in rows]
        values = np.empty(len(cells))
        bad = None
        for i, c in enumerate(cells):
            if not c:
                values[i] = np.nan
                continue
            try:
                values[i] = float(c)
            except ValueError:
                bad = i
                break
        if bad is None:
            out[col] = values
        elif col in strict:
            raise FlightDataError(
                f"{name}: non-numeric value {cells[bad]!r} in column '{col}' at row {bad} "
                f"(line {line_nos[bad]}); write a number there or remove the row"
            )
        # else: a non-numeric extra column, dropped (fwid ignores extra columns)
    return out, np.array(line_nos)
