"""How `import fwid` sets JAX up: float64, and one CPU device per core. Public JAX
configuration only (`jax.config.update`), done before JAX runs anything.

- `jax_enable_x64`: output-error estimation needs float64 (Gauss-Newton with tight tolerances
  never terminates in float32). `FWID_NO_X64=1` leaves JAX's default.
- `jax_num_cpu_devices`: JAX's default is one CPU device, on which XLA runs each flight loop
  on one core; with one device per core (at most 8) [`fwid.fit_each`][] and joint fits
  spread their flights over the cores. Only when nobody chose a count (`jax_num_cpu_devices`,
  `--xla_force_host_platform_device_count` in `XLA_FLAGS`) and JAX has run nothing yet: JAX
  refuses the option afterwards (a `RuntimeError`), and fwid then keeps what JAX has.
  `FWID_CPU_DEVICES=N` asks for N; `FWID_CPU_DEVICES=1` leaves JAX's default.
"""

from __future__ import annotations

import os
import warnings

import jax

MAX_CPU_DEVICES = 8


def enable_x64(environ=os.environ) -> bool:
    """Turn on float64 unless `FWID_NO_X64` is set; returns whether it did."""
    if environ.get("FWID_NO_X64"):
        return False
    jax.config.update("jax_enable_x64", True)
    return True


def wanted_cpu_devices(environ=os.environ) -> int | None:
    """The CPU device count fwid asks for, or `None` where the user chose (or left) it."""
    wanted = environ.get("FWID_CPU_DEVICES")
    if wanted is None:
        if "xla_force_host_platform_device_count" in environ.get("XLA_FLAGS", ""):
            return None
        cores = (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                 else (os.cpu_count() or 1))
        return min(cores, MAX_CPU_DEVICES)
    try:
        n = int(wanted)
    except ValueError:
        warnings.warn(f"FWID_CPU_DEVICES={wanted!r} is not a whole number of CPU devices; "
                      "JAX's default kept (set FWID_CPU_DEVICES=N, or 1 for JAX's default)",
                      stacklevel=3)
        return None
    return n if n > 1 else None


def cpu_devices(environ=os.environ) -> int | None:
    """Ask JAX for one CPU device per core (see the module docstring); returns the count set,
    or `None` when it left JAX's setting alone."""
    n = wanted_cpu_devices(environ)
    if n is None or n <= 1 or jax.config.jax_num_cpu_devices != -1:
        return None
    try:
        jax.config.update("jax_num_cpu_devices", n)
    except RuntimeError:  # JAX has already started its backends: too late, keep them
        return None
    return n
