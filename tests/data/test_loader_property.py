"""The loader is unbreakable: whatever a lab's export does to a flight file (a byte-order
mark, CRLF, quotes, semicolons, cut rows, stray text, empty cells, a header alone), it loads
or stops with a FlightDataError (exit 2 on the command line); never another exception."""

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fwid import FlightDataError
from fwid.data import Flight, load_flight

from .helpers import lon_flight

_COLS = lon_flight(duration=1.0)
_HEADER = list(_COLS)
_ROWS = np.column_stack([_COLS[c] for c in _HEADER])


def _text(rows: int, sep: str, quote: bool, drop_cols: int) -> list[str]:
    names = _HEADER[: len(_HEADER) - drop_cols] if drop_cols else _HEADER
    head = [f'"{n}"' if quote else n for n in names]
    lines = [sep.join(head)]
    for r in _ROWS[:rows]:
        lines.append(sep.join(f"{v:.8g}" for v in r[: len(names)]))
    return lines


mangle = st.sampled_from(["none", "bom", "crlf", "trailing_comma", "blank_lines", "cut_row",
                          "stray_text", "empty_cell", "nan_text", "tabs", "dup_header",
                          "swap_chars", "binary"])


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rows=st.integers(0, 200), sep=st.sampled_from([",", ";", "\t", ", "]),
       quote=st.booleans(), drop=st.integers(0, 5), how=st.lists(mangle, max_size=3),
       seed=st.integers(0, 2**16))
def test_mangled_files_load_or_say_why(rows, sep, quote, drop, how, seed):
    rng = np.random.default_rng(seed)
    lines = _text(rows, sep, quote, drop)
    for h in how:
        k = int(rng.integers(0, len(lines)))
        if h == "trailing_comma":
            lines = [ln + sep for ln in lines]
        elif h == "blank_lines":
            lines.insert(k, "")
        elif h == "cut_row" and len(lines) > 1:
            lines[k] = lines[k][: max(1, len(lines[k]) // 2)]
        elif h == "stray_text":
            lines.insert(k, "# exported by LabTool v2; units: SI")
        elif h == "empty_cell" and k > 0:
            cells = lines[k].split(sep)
            cells[int(rng.integers(0, len(cells)))] = ""
            lines[k] = sep.join(cells)
        elif h == "nan_text" and k > 0:
            lines[k] = lines[k].replace("0", "nan", 1)
        elif h == "tabs":
            lines[k] = lines[k].replace(sep, "\t")
        elif h == "dup_header":
            lines.insert(k, lines[0])
        elif h == "swap_chars" and lines[k]:
            i = int(rng.integers(0, len(lines[k])))
            lines[k] = lines[k][:i] + "x" + lines[k][i + 1:]
    text = ("\r\n" if "crlf" in how else "\n").join(lines)
    data = text.encode()
    if "bom" in how:
        data = b"\xef\xbb\xbf" + data
    if "binary" in how:
        data = data[: len(data) // 2] + bytes(rng.integers(0, 256, 64, dtype=np.uint8))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "lon_0.csv"
        path.write_bytes(data)
        try:
            flight = load_flight(path)
        except FlightDataError as e:
            msg = str(e)
            assert msg and "\n" not in msg and str(path) in msg, msg
            return
        assert isinstance(flight, Flight) and flight.n >= 2
