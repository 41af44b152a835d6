"""How fwid sets JAX up: float64, one CPU device per core, and a persistent compilation
cache. Public JAX configuration only (`jax.config.update`), done before JAX runs anything.

`import fwid` does not import JAX (the command line answers `--help` and bad input without
it): [`on_jax_import`][] runs [`setup`][] now if JAX is already imported, else right after
JAX's first import, wherever that happens (`import jax` by the user, or a fwid module).

- `jax_enable_x64`: output-error estimation needs float64 (Gauss-Newton with tight tolerances
  never terminates in float32). `FWID_NO_X64=1` leaves JAX's default.
- `jax_num_cpu_devices`: JAX's default is one CPU device, on which XLA runs each flight loop
  on one core; with one device per core (at most 8) [`fwid.fit_each`][] and joint fits
  spread their flights over the cores. Only when nobody chose a count (`jax_num_cpu_devices`,
  `--xla_force_host_platform_device_count` in `XLA_FLAGS`) and JAX has run nothing yet: JAX
  refuses the option afterwards (a `RuntimeError`), and fwid then keeps what JAX has.
  `FWID_CPU_DEVICES=N` asks for N; `FWID_CPU_DEVICES=1` leaves JAX's default.
- `jax_compilation_cache_dir`: compiled programs are kept on disk, so a new process (a second
  `fwid identify`, a notebook after a restart) loads them instead of compiling again. The
  folder is `$XDG_CACHE_HOME/fwid/jax` (`~/.cache/fwid/jax` without it); `FWID_JAX_CACHE=DIR`
  moves it, `FWID_JAX_CACHE=0` (or `off`) turns it off. A cache the user configured
  (`jax_compilation_cache_dir`, `JAX_COMPILATION_CACHE_DIR`) or turned off
  (`jax_enable_compilation_cache`) is left alone. JAX writes each entry atomically, so two
  processes may share the folder.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import os
import sys
import warnings
from pathlib import Path

MAX_CPU_DEVICES = 8
CACHE_OFF = ("0", "off", "no", "false", "none")


def enable_x64(environ=os.environ) -> bool:
    """Turn on float64 unless `FWID_NO_X64` is set; returns whether it did."""
    if environ.get("FWID_NO_X64"):
        return False
    import jax

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
    import jax

    n = wanted_cpu_devices(environ)
    if n is None or n <= 1 or jax.config.jax_num_cpu_devices != -1:
        return None
    try:
        jax.config.update("jax_num_cpu_devices", n)
    except RuntimeError:  # JAX has already started its backends: too late, keep them
        return None
    return n


def cache_folder(environ=os.environ) -> Path | None:
    """The compilation cache folder fwid asks for: `FWID_JAX_CACHE`, else
    `$XDG_CACHE_HOME/fwid/jax` or `~/.cache/fwid/jax`; `None` when turned off."""
    wanted = environ.get("FWID_JAX_CACHE", "").strip()
    if wanted.lower() in CACHE_OFF:
        return None
    if wanted:
        return Path(wanted).expanduser()
    base = environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "fwid" / "jax"


def compilation_cache(environ=os.environ) -> Path | None:
    """Turn on JAX's persistent compilation cache in [`cache_folder`][], for every compile
    (fwid's take well under JAX's default threshold of 1 s each); returns the folder, or
    `None` when turned off or when the user configured JAX's cache."""
    import jax

    folder = cache_folder(environ)
    if (folder is None or jax.config.jax_compilation_cache_dir
            or not jax.config.jax_enable_compilation_cache):
        return None
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", -1)
    return folder


def setup(environ=os.environ) -> None:
    """All of the above, once JAX is imported."""
    enable_x64(environ)
    cpu_devices(environ)
    compilation_cache(environ)


class _AfterImport(importlib.abc.MetaPathFinder):
    """Runs `then()` right after the module `name` is first imported (then steps aside)."""

    def __init__(self, name, then):
        self.name, self.then = name, then

    def find_spec(self, fullname, path=None, target=None):
        if fullname != self.name:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            self.then()

        spec.loader.exec_module = exec_module
        return spec


def on_jax_import(then=setup) -> None:
    """Run `then()` now if JAX is imported, else right after JAX's first import."""
    if "jax" in sys.modules:
        then()
    elif not any(isinstance(f, _AfterImport) for f in sys.meta_path):
        sys.meta_path.insert(0, _AfterImport("jax", then))
