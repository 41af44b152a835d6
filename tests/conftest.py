"""Shared test setup: importing fwid turns on JAX's float64 mode for every test."""

import fwid  # noqa: F401
