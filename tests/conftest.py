"""Shared test setup: importing fwid turns on JAX's float64 mode for every test (once JAX is
imported), and the tests keep no compilation cache on disk (`FWID_JAX_CACHE=off`, unless set):
nothing is written to the user's home."""

import os

os.environ.setdefault("FWID_JAX_CACHE", "off")

import fwid  # noqa: E402, F401
