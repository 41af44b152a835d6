"""Columns of a recording kept as arrays: MATLAB (`.mat`, v5 through scipy, v7.3 through
h5py), NumPy (`.npz`) and HDF5 (`.h5`, `.hdf5`) files.

A recording map names a column there as `NAME`, `NAME[i]` or `NAME[i,j]`: `NAME` a variable,
or a dotted path into MATLAB structs or HDF5 groups (`take.RigidBodies.Positions`), the
indices 0-based into the variable's axes other than its sample axis (the axis as long as the
time base). Each named column comes back as one array over the samples; a variable one or two
samples longer or shorter than the time base is trimmed to the common length, with a warning.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._errors import FlightDataError

#: The suffixes of array files.
ARRAY_SUFFIXES = (".mat", ".npz", ".h5", ".hdf5")
#: The most samples a variable may differ from the time base by and still be trimmed.
MAX_TRIM = 2
#: How many of a file's variable names an error lists.
LISTED = 12
_SPEC = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[\s*([0-9,\s]*)\s*\])?\s*$")


def is_array_file(path) -> bool:
    """Whether `path` names an array file (`ARRAY_SUFFIXES`)."""
    return Path(path).suffix.lower() in ARRAY_SUFFIXES


def _is_hdf5(path: Path) -> bool:
    with open(path, "rb") as fh:
        head = fh.read(520)
    return b"\x89HDF\r\n\x1a\n" in head[:8] or head[512:520] == b"\x89HDF\r\n\x1a\n"


def _load(path: Path):
    """The file's tree of variables: nested dicts (MATLAB v5, npz) or an open h5py File,
    and whether HDF5 arrays are stored transposed (MATLAB v7.3 writes column-major)."""
    try:
        if path.suffix.lower() == ".npz":
            with np.load(path, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}, False
        if path.suffix.lower() == ".mat" and not _is_hdf5(path):
            from scipy.io import loadmat

            return {k: v for k, v in loadmat(path).items() if not k.startswith("__")}, False
        import h5py

        return h5py.File(path, "r"), path.suffix.lower() == ".mat"
    except ImportError as e:
        raise FlightDataError(f"{path}: reading it needs {e.name} (pip install {e.name})") from None
    except (OSError, ValueError, NotImplementedError) as e:
        raise FlightDataError(f"{path}: cannot read the file ({e})") from None


def _children(node) -> dict:
    """The named children of a node: dict entries, HDF5 group members, or the fields of a
    MATLAB struct (a 1 x 1 record array)."""
    if isinstance(node, dict):
        return node
    if hasattr(node, "keys") and hasattr(node, "visit"):  # an h5py Group
        return {k: node[k] for k in node.keys() if not k.startswith("#")}
    if isinstance(node, np.ndarray) and node.dtype.names and node.size == 1:
        return {k: node[k].flat[0] for k in node.dtype.names}
    return {}


def variables(tree, prefix: str = "") -> list[str]:
    """Every numeric variable of a file, as dotted paths."""
    out = []
    for k, v in _children(tree).items():
        name = f"{prefix}{k}"
        sub = _children(v)
        if sub:
            out += variables(v, name + ".")
        elif getattr(v, "dtype", None) is not None and np.issubdtype(v.dtype, np.number):
            out.append(name)
    return out


def _listing(tree) -> str:
    names = variables(tree)
    return ", ".join(names[:LISTED]) + (", ..." if len(names) > LISTED else "")


def _variable(tree, name: str, transposed: bool):
    """The array at dotted path `name`, or None."""
    node = tree
    for part in name.split("."):
        kids = _children(node)
        if part not in kids:
            return None
        node = kids[part]
    if getattr(node, "dtype", None) is None or _children(node):
        return None
    a = np.asarray(node[()] if not isinstance(node, np.ndarray) else node)
    if not np.issubdtype(a.dtype, np.number):
        return None
    return a.T if transposed else a


def _parse(spec: str):
    m = _SPEC.match(spec)
    if m is None:
        return None
    idx = () if m.group(2) is None else tuple(
        int(s) for s in m.group(2).replace(" ", "").split(",") if s != "")
    if m.group(2) is not None and not idx:
        return None
    return m.group(1), idx


def read_arrays(path, wanted: list[tuple[str, str]], time: tuple[str, str] | None = None):
    """The columns a map names in an array file.

    **Arguments:**
    - `path`: the file;
    - `wanted`: `(key, spec)` pairs: the map's key (for messages) and the column it names;
    - `time`: the `(key, spec)` of the time base (a vector, e.g. 1 x N), whose length sets
      the sample axis; without it, the longest axis of the first wanted variable does.

    **Returns:** `(columns, warnings)`: a dict from each spec to its samples (all of one
    length), and one warning when variables were trimmed to the common length. A missing
    variable, an index out of range, or a variable whose length is more than `MAX_TRIM`
    samples off the time base's is a `FlightDataError` naming the key, the file and (for a
    missing one) the variables the file holds.
    """
    path = Path(path)
    tree, transposed = _load(path)
    try:
        raw = {}
        for key, spec in ([time] if time else []) + list(wanted):
            parsed = _parse(spec)
            if parsed is None:
                raise FlightDataError(f"{key}: {spec!r} is not a column of an array file; write "
                                      "NAME, NAME[i] or NAME[i,j] (0-based)")
            a = _variable(tree, parsed[0], transposed)
            if a is None:
                raise FlightDataError(f"{key}: no variable {parsed[0]!r} in {path.name}; it "
                                      f"holds {_listing(tree)}")
            raw[spec] = (key, a, parsed[1])
    finally:
        if hasattr(tree, "close"):
            tree.close()
    if time is not None:
        key, a, idx = raw[time[1]]
        if a.size != max(a.shape, default=0) or idx:
            shape = " x ".join(map(str, a.shape))
            raise FlightDataError(f"{key}: {time[1]!r} in {path.name} is {shape}, not a vector "
                                  "of time stamps")
        n = a.size
    else:
        n = max(next(iter(raw.values()))[1].shape)
    cols = {}
    for spec, (key, a, idx) in raw.items():
        cols[spec] = _samples(a, idx, n, key, spec, path.name)
    lengths = {len(v) for v in cols.values()}
    common = min(lengths)
    notes = []
    if len(lengths) > 1:
        longer = sorted({s for s, v in cols.items() if len(v) > common})
        notes.append(f"{path.name}: {', '.join(longer)} hold{'s' if len(longer) == 1 else ''} "
                     f"{max(lengths) - common} more sample(s) than the other columns "
                     f"({max(lengths)} against {common}); trimmed to the common {common}")
        cols = {s: v[:common] for s, v in cols.items()}
    return cols, notes


def _samples(a: np.ndarray, idx: tuple, n: int, key, spec, name) -> np.ndarray:
    """The samples of array `a` at indices `idx` into its axes other than the sample axis
    (the axis of length `n`, else one within `MAX_TRIM` of it)."""
    shape = " x ".join(map(str, a.shape))
    axes = [i for i, s in enumerate(a.shape) if s == n]
    axes = axes or [i for i, s in enumerate(a.shape) if abs(s - n) <= MAX_TRIM]
    if not axes:
        big = max(a.shape, default=0)
        raise FlightDataError(f"{key}: {spec!r} in {name} is {shape}: {big} samples against the "
                              f"time base's {n}; a variable may differ by at most {MAX_TRIM} "
                              "(check that the map names the take's own variables)")
    a = np.moveaxis(a, axes[0], 0)
    rest = a.shape[1:]
    if len(idx) != len(rest):
        keep = [i for i, s in enumerate(rest) if s != 1]
        if len(idx) == len(keep):
            a = a.reshape((a.shape[0],) + tuple(rest[i] for i in keep))
            rest = a.shape[1:]
    if len(idx) != len(rest):
        per = " x ".join(map(str, rest)) or "1"
        raise FlightDataError(f"{key}: {spec!r} in {name} is {shape}, {per} per sample: give "
                              f"{len(rest)} 0-based index(es) in brackets, e.g. "
                              f"{spec.split('[')[0]}[{','.join('0' * len(rest))}]")
    for i, (k, s) in enumerate(zip(idx, rest)):
        if k >= s:
            raise FlightDataError(f"{key}: {spec!r} in {name}: index {k} is out of range for "
                                  f"an axis of {s} (indices are 0-based)")
    return np.asarray(a[(slice(None),) + tuple(idx)], dtype=float).reshape(a.shape[0])
