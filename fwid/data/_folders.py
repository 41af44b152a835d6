"""Which files a list of paths stands for (a folder: its CSV files in natural order), and
the names that tell them apart; no JAX."""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path

from .._errors import FlightDataError


def _flatten(items) -> list:
    out = []
    for it in items:
        if isinstance(it, (list, tuple)):
            out.extend(_flatten(it))
        else:
            out.append(it)
    return out


def natural_key(name: str) -> list:
    """Sort key that orders numbers by value: `lon_2` before `lon_10`."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def _csv_files(folder: Path) -> list[Path]:
    return sorted(
        (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() == ".csv"),
        key=lambda p: natural_key(p.name),
    )


def flight_names(files: Sequence[Path]) -> list[str]:
    """Names that tell the flights apart: each file's path relative to the folder the files
    have in common (`lon_0.csv` for one folder, `clean/lon_0.csv` and `demo/lon_0.csv` for
    two), in `/` form."""
    parents = [str(f.resolve().parent) for f in files]
    root = Path(os.path.commonpath(parents)) if parents else Path(".")
    return [f.resolve().relative_to(root).as_posix() for f in files]


def flight_files(*paths_or_folders) -> list[Path]:
    """The CSV files that `paths_or_folders` (files, folders, lists of them) stand for: a
    folder is its `*.csv` files in natural order ([`natural_key`][]).

    Raises a [`fwid.FlightDataError`][] when no path is given, a path does not exist, or a
    folder holds no CSV file.
    """
    items = _flatten(paths_or_folders)
    if not items:
        raise FlightDataError("no flight files given; pass CSV files or folders of them")
    files: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = _csv_files(p)
            if not found:
                raise FlightDataError(
                    f"{p}: folder holds no .csv flight files; point to the folder with the "
                    "flights"
                )
            files.extend(found)
        elif p.is_file():
            files.append(p)
        else:
            raise FlightDataError(f"{p}: no such file or folder")
    return files
