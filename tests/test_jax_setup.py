"""`import fwid` sets JAX up through its public configuration only: float64, and one CPU
device per core unless the user chose; each case in a fresh process (JAX is set up once)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from fwid import _jax_setup

PROBE = ("import json, jax, fwid; print(json.dumps({'devices': len(jax.devices('cpu')), "
         "'x64': bool(jax.config.jax_enable_x64)}))")


def _probe(**env):
    clean = {k: v for k, v in os.environ.items()
             if k not in ("FWID_CPU_DEVICES", "FWID_NO_X64", "XLA_FLAGS")}
    clean.update(env)
    out = subprocess.run([sys.executable, "-c", PROBE], env=clean, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cores():
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


@pytest.mark.parametrize("env, devices, x64", [
    ({}, None, True),                                   # one per core, at most 8
    ({"FWID_CPU_DEVICES": "3"}, 3, True),
    ({"FWID_CPU_DEVICES": "1"}, 1, True),                # JAX's default
    ({"XLA_FLAGS": "--xla_force_host_platform_device_count=5"}, 5, True),  # the user's choice
    ({"FWID_NO_X64": "1", "FWID_CPU_DEVICES": "2"}, 2, False),
])
def test_import_sets_up_jax(env, devices, x64):
    if jax_default_is_not_cpu():
        pytest.skip("not a CPU backend")
    got = _probe(**env)
    want = min(_cores(), _jax_setup.MAX_CPU_DEVICES) if devices is None else devices
    assert got == {"devices": want, "x64": x64}


def jax_default_is_not_cpu():
    import jax

    return jax.default_backend() != "cpu"


def test_too_late_is_harmless():
    """Once JAX has run (here: the test session), asking again changes nothing and raises
    nothing; a count the user set in JAX's config is kept."""
    import jax

    jax.numpy.zeros(1).block_until_ready()
    assert _jax_setup.cpu_devices({"FWID_CPU_DEVICES": "7"}) is None


def test_bad_count_warns():
    with pytest.warns(UserWarning, match="FWID_CPU_DEVICES='many'"):
        assert _jax_setup.wanted_cpu_devices({"FWID_CPU_DEVICES": "many"}) is None
    assert _jax_setup.wanted_cpu_devices({"XLA_FLAGS": "--xla_force_host_platform_device_count=4"}) is None
    assert _jax_setup.wanted_cpu_devices({"FWID_CPU_DEVICES": "4"}) == 4


def test_cache_folder_default_moved_and_off(tmp_path):
    assert _jax_setup.cache_folder({"XDG_CACHE_HOME": str(tmp_path)}) == tmp_path / "fwid" / "jax"
    assert _jax_setup.cache_folder({"FWID_JAX_CACHE": str(tmp_path / "c")}) == tmp_path / "c"
    for off in ("0", "off", "OFF", "false"):
        assert _jax_setup.cache_folder({"FWID_JAX_CACHE": off}) is None


CACHE_PROBE = ("import fwid, jax, json; jax.jit(lambda x: x * 2 + 1)(jax.numpy.ones(3))"
               ".block_until_ready(); print(json.dumps(jax.config.jax_compilation_cache_dir))")


@pytest.mark.parametrize("env, where", [
    ({"FWID_JAX_CACHE": "{tmp}/mine"}, "{tmp}/mine"),      # moved
    ({"XDG_CACHE_HOME": "{tmp}/xdg"}, "{tmp}/xdg/fwid/jax"),  # the per-user default
    ({"FWID_JAX_CACHE": "off"}, None),
    ({"JAX_COMPILATION_CACHE_DIR": "{tmp}/users"}, "{tmp}/users"),  # the user's own: kept
])
def test_compilation_cache_on_by_default(tmp_path, env, where):
    env = {k: v.format(tmp=tmp_path) for k, v in env.items()}
    clean = {k: v for k, v in os.environ.items()
             if k not in ("FWID_JAX_CACHE", "XDG_CACHE_HOME", "JAX_COMPILATION_CACHE_DIR")}
    out = subprocess.run([sys.executable, "-c", CACHE_PROBE], env={**clean, **env},
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    where = None if where is None else where.format(tmp=tmp_path)
    assert got == where
    if where is not None and "JAX_COMPILATION_CACHE_DIR" not in env:  # fwid's thresholds:
        # even this tiny program is kept
        assert any(Path(where).iterdir())


def test_import_fwid_does_not_import_jax():
    """JAX (and so its setup) comes with the first fwid function used, or the user's import."""
    probe = ("import sys, fwid; assert 'jax' not in sys.modules; import jax; "
             "assert jax.config.jax_enable_x64; fwid.fit; assert 'fwid.estimate' in sys.modules")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
