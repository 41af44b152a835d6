"""Write simulated flights to disk in the flight-data format."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ._delfly import DELFLY
from ._simulate import COLUMNS, DEFAULT_AMPLITUDE, simulate_flight

#: Input types cycled through by `write_flights` (flight i gets `INPUT_CYCLE[i % 4]`).
INPUT_CYCLE = ("3211", "doublet", "211", "pulse")


def write_csv(path, flight: dict, truth_columns: bool = False) -> Path:
    """Write one flight (a `simulate_flight` result) as CSV with the `COLUMNS` header;
    17 significant digits, so noise-free flights survive the round trip exactly. With
    `truth_columns`, the exact loads are added as extra columns `X_true, ..., N_true` (which
    fwid's loader keeps and every model ignores): the error floor of the true model, for
    benchmarks."""
    path = Path(path)
    names = list(COLUMNS)
    cols = [np.asarray(flight[c], dtype=float) for c in COLUMNS]
    if truth_columns:
        for k, v in flight["meta"]["loads_true"].items():
            names.append(f"{k}_true")
            cols.append(np.asarray(v, dtype=float))
    data = np.column_stack(cols)
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    return path


def write_sidecar(path, flight: dict) -> Path:
    """Write the sidecar `NAME.json`: `{"trim": {..}, "first_input": k, "truth": {..}}`
    (the true trim, the index of the first input sample, and the true parameters, effect
    and simulation options; the loader ignores `truth`)."""
    path = Path(path)
    meta = flight["meta"]
    side = {"trim": meta["trim"], "truth": meta["truth"]}
    if meta["first_input"] is not None:
        side["first_input"] = int(meta["first_input"])
    path.write_text(json.dumps(side, indent=2) + "\n")
    return path


def write_vehicle(out_dir, vehicle=DELFLY) -> Path:
    """Write `vehicle.json` (mass, Ix, Iy, Iz, Ixz, g) into `out_dir`."""
    path = Path(out_dir) / "vehicle.json"
    path.write_text(json.dumps(vehicle.vehicle(), indent=2) + "\n")
    return path


def write_flights(
    out_dir,
    n_flights: int = 4,
    axis: str = "lon",
    seed: int = 0,
    effect: str | tuple = "none",
    strength: float | tuple = 1.0,
    truth_columns: bool = False,
    form: str | tuple | None = None,
    prefix: str | None = None,
    **kw,
) -> list[Path]:
    """Simulate `n_flights` flights and write `lon_0.csv, lon_1.csv, ...` (or `lat_*`), their
    sidecars `lon_0.json, ...` and `vehicle.json` into `out_dir` (created if needed).
    `prefix` replaces the axis in the names (`prefix="train"`: `train_0.csv, ...`), so that
    sets written into one folder by separate calls do not overwrite each other.

    Flight `i` is drawn from `numpy.random.default_rng(seed + i)`: the input type cycles
    through `INPUT_CYCLE` (3211, doublet, 211, pulse), the amplitude is
    `DEFAULT_AMPLITUDE[axis] x U(0.8, 1.25)`, the quiet start lasts `U(0.8, 1.3)` s, and the
    simulation seed is drawn from the same generator. Any of `input`, `amplitude`, `start`
    or `seed`-independent options of `simulate_flight` given in `kw` (e.g. `noise`,
    `flapping`, `drift`, `duration`) apply to every flight. Deterministic by `seed`.
    `truth_columns`: also write the exact loads (`write_csv`). `effect`, `strength`, `form`:
    the unmodelled effect(s) and form(s) (`simulate_flight`); `vehicle` in `kw` (e.g.
    `random_vehicle(seed)`) is simulated and written to `vehicle.json`.

    **Returns:** the CSV paths, in order.
    """
    if n_flights < 0:
        raise ValueError(f"n_flights must be >= 0, got {n_flights}")
    stem = axis if prefix is None else prefix
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    vehicle = kw.get("vehicle", DELFLY)
    write_vehicle(out, vehicle)
    paths = []
    for i in range(n_flights):
        rng = np.random.default_rng(seed + i)
        amp = DEFAULT_AMPLITUDE[axis] * rng.uniform(0.8, 1.25)
        start = rng.uniform(0.8, 1.3)
        sim_seed = int(rng.integers(2**31 - 1))
        args = {"input": INPUT_CYCLE[i % len(INPUT_CYCLE)], "amplitude": amp, "start": start}
        args.update(kw)
        flight = simulate_flight(axis=axis, seed=sim_seed, effect=effect, strength=strength,
                                 form=form, **args)
        csv = write_csv(out / f"{stem}_{i}.csv", flight, truth_columns)
        write_sidecar(csv.with_suffix(".json"), flight)
        paths.append(csv)
    return paths
