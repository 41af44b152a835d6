"""The batched estimator kept whole on disk (`jax.export`): the same estimates
whether traced, kept or read back; a program is kept only under a key that describes it; a
user's model is traced as before.

The fits run in a process of their own with `EQX_ON_ERROR=nan`, as the `fwid` executable
sets it: a program with Equinox's raising checks (host callbacks) cannot be exported."""

import copy
import json
import os
import subprocess
import sys

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.estimate import _exported
from fwid.models import longitudinal

PROBE = r"""
import copy, json, os, sys
from pathlib import Path
import numpy as np
import fwid
from fwid.synth import write_flights

folder, cache = Path(sys.argv[1]), Path(sys.argv[2])
write_flights(folder, n_flights=2, axis="lon", seed=11, duration=3.0)
model = fwid.longitudinal()
exps = [fwid.experiment(fwid.cycle_averaged(f), model) for f in fwid.load_flights(folder)]

def estimates(m):
    return [np.asarray(r.theta).tolist() for r in fwid.fit_each(m, exps)]

def kept():
    return sorted(p.name for p in (cache / "exported").glob("*.jaxexport"))

out = {}
os.environ["FWID_JAX_CACHE"] = "off"
out["traced"] = estimates(model)
os.environ["FWID_JAX_CACHE"] = str(cache)
out["kept"] = estimates(model)
out["files_after_kept"] = kept()
out["again"] = estimates(model)  # this process's loaded program
from fwid.estimate import _exported
_exported._RUNNERS.clear()  # as a new process: read back from the file
out["read"] = estimates(model)
out["files_after_read"] = kept()

def f(x, u, p, c):  # a user's function: not fwid's, so not kept
    return model.f(x, u, p, c)

user = copy.copy(model)
object.__setattr__(user, "f", f)
out["user"] = estimates(user)
out["files_after_user"] = kept()
print(json.dumps(out))
"""


def test_kept_program_gives_the_traced_estimates(tmp_path):
    env = {**os.environ, "EQX_ON_ERROR": "nan", "FWID_JAX_CACHE": "off"}
    proc = subprocess.run([sys.executable, "-c", PROBE, str(tmp_path / "f"),
                           str(tmp_path / "cache")], capture_output=True, text=True, env=env,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    traced = np.array(out["traced"])
    assert out["files_after_kept"]  # the full-R fit (and the diagonal one, if it fell back)
    assert out["files_after_read"] == out["files_after_kept"]  # read, not kept again
    np.testing.assert_allclose(out["kept"], traced, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(out["again"], traced, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(out["read"], traced, rtol=1e-12, atol=1e-14)
    assert out["files_after_user"] == out["files_after_kept"]  # the user's model: none kept
    np.testing.assert_allclose(out["user"], traced, rtol=1e-12, atol=1e-14)


def test_key_describes_what_shapes_the_program():
    d = _exported.describe
    # arrays by shape and dtype only (their values are the program's inputs) ...
    assert d(jnp.zeros(3)) == d(jnp.ones(3)) != d(jnp.zeros(4))
    # ... except in a static field, which the program holds as a constant
    assert d(np.zeros(3), static=True) != d(np.ones(3), static=True)
    assert d({"a": 1.0, "b": (2, "x")}) != d({"a": 1.5, "b": (2, "x")})
    assert d(longitudinal()) == d(longitudinal())
    assert d(longitudinal()) != d(fwid.lateral())

    def local(x):
        return x

    user = copy.copy(longitudinal())
    object.__setattr__(user, "f", local)
    for foreign in (lambda x: x, local, object(), user):
        with pytest.raises(_exported._Unkeyable):
            d(foreign)
