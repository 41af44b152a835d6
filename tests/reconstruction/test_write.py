"""Writing the reconstructed flights."""

from __future__ import annotations

import io

import numpy as np

from fwid.reconstruction._write import flight_csv


def test_flight_csv_is_numpys_savetxt_text():
    """The flight's CSV text equals `np.savetxt`'s at 12 significant digits, to the byte:
    NaN, infinities, minus zero and values over sixteen decades included."""
    rng = np.random.default_rng(0)
    cols = {k: rng.normal(size=500) * 10.0 ** rng.integers(-8, 8)
            for k in ("t", "u", "w", "q", "theta", "X", "Z", "M")}
    cols["u"][5], cols["w"][7], cols["q"][9] = np.nan, -np.inf, -0.0
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack(list(cols.values())), delimiter=",",
               header=",".join(cols), comments="", fmt="%.12g")
    assert flight_csv(cols) == buf.getvalue()
    assert flight_csv({"t": np.array([0.0, 0.005])}) == "t\n0\n0.005\n"
