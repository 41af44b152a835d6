"""Checks on the command line's input paths that need no JAX: a missing file is answered at
once (the same one line as [`fwid.load_flights`][], which checks everything else)."""

from __future__ import annotations

from pathlib import Path

from .._errors import FlightDataError


def check_paths(*groups) -> None:
    """Every path in the lists `groups` exists, else a `FlightDataError` naming it."""
    for p in (p for group in groups for p in group or ()):
        if not Path(p).exists():
            raise FlightDataError(f"{p}: no such file or folder")
