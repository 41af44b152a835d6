"""`fit_each` over two processes (`jax.distributed`, CPU collectives over 127.0.0.1) equals
`fit_each` in one process."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fwid
from tests.estimate._distributed_worker import NO_COLLECTIVES, flights, free_port

ROOT = Path(__file__).resolve().parents[2]


def _has_cpu_collectives() -> bool:
    import jax

    return "jax_cpu_collectives_implementation" in jax.config.values


def test_two_processes_equal_one(tmp_path):
    """4 flights fitted by two processes of one CPU device each (a global mesh of 2): the
    estimates equal one process's to 1e-9."""
    if not _has_cpu_collectives():
        pytest.skip("this JAX has no CPU collectives (jax_cpu_collectives_implementation)")
    port, out = free_port(), tmp_path / "theta.npy"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    procs = [subprocess.Popen([sys.executable, "-m", "tests.estimate._distributed_worker",
                               str(pid), "2", str(port), str(out)], cwd=ROOT, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
             for pid in (0, 1)]
    try:
        logs = [p.communicate(timeout=240)[0] for p in procs]
    finally:  # one that failed to start leaves the other waiting for it
        for p in procs:
            if p.poll() is None:
                p.kill()
    if any(p.returncode == NO_COLLECTIVES for p in procs):
        pytest.skip("this JAX build cannot join a CPU cluster: "
                    + next(log for log in logs if "no CPU collectives" in log)[-300:])
    assert all(p.returncode == 0 for p in procs), "\n".join(log[-2000:] for log in logs)
    one = fwid.fit_each(fwid.longitudinal(), flights())
    np.testing.assert_allclose(np.load(out), np.stack([np.asarray(r.theta) for r in one]),
                               rtol=1e-9, atol=1e-12)
