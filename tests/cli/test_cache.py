"""The `fwid` executable's compiled programs all go to JAX's persistent compilation cache.

JAX does not write a program with a host callback (Equinox's raising runtime checks) to the
cache; `fwid.cli.run` sets `EQX_ON_ERROR=nan` so that none has one. Without it the batched
fit and the simulation were compiled again by every process.
"""

from __future__ import annotations

import os
import subprocess
import sys

from fwid.synth import write_flights

PROBE = """
import logging, sys
logging.basicConfig(level=logging.WARNING)
logging.getLogger("jax._src.compiler").setLevel(logging.DEBUG)
from fwid.cli import run
sys.exit(run(sys.argv[1:]))
"""


def _identify(folder, out, cache, extra_env=None):
    env = {k: v for k, v in os.environ.items() if k != "EQX_ON_ERROR"}
    env.update({"FWID_JAX_CACHE": str(cache), **(extra_env or {})})
    return subprocess.run([sys.executable, "-c", PROBE, "identify", str(folder), "--model",
                           "lon", "--out", str(out), "--quiet", "--figures", "none"],
                          capture_output=True, text=True, env=env, timeout=600)


def test_every_program_is_cached(tmp_path):
    write_flights(tmp_path / "f", n_flights=2, axis="lon", seed=3, duration=3.0)
    proc = _identify(tmp_path / "f", tmp_path / "out", tmp_path / "cache")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "PERSISTENT COMPILATION CACHE MISS" in proc.stderr  # the probe sees the cache
    assert "Not writing persistent cache entry" not in proc.stderr, [
        ln for ln in proc.stderr.splitlines() if "Not writing" in ln]
    # a second process compiles nothing: every program is a cache hit
    again = _identify(tmp_path / "f", tmp_path / "out2", tmp_path / "cache")
    assert again.returncode == 0, again.stderr[-2000:]
    assert "PERSISTENT COMPILATION CACHE MISS" not in again.stderr

