"""Shared test setup: importing fwid turns on JAX's float64 mode for every test (once JAX is
imported), and the tests share one compilation cache on disk in the system's temporary folder
(`FWID_JAX_CACHE`, unless set): the pytest-xdist workers and the command-line processes the
tests start load what another has compiled instead of compiling it again, and nothing is
written to the user's home. JAX keys each entry by the program, the options and its own
version, so an entry from other code is never used in its place."""

import os
import tempfile
from pathlib import Path

os.environ.setdefault("FWID_JAX_CACHE",
                      str(Path(tempfile.gettempdir()) / f"fwid-tests-{os.getuid()}" / "jax"))

import fwid  # noqa: E402, F401
