"""The per-take work on worker processes: the same flights, byte for byte, as in one process;
a bad take among them reported, not raised; no fork once JAX runs."""

import json
import multiprocessing
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import fwid
from fwid.reconstruction import _workers
from fwid.reconstruction._read import read_raw

from .helpers import Motion, write_motive

ROOT = Path(__file__).resolve().parents[2]
T = np.arange(0, 3, 0.005)


def test_run_all_keeps_order_and_returns_errors(tmp_path):
    """On a real pool (spawned: this process runs JAX), in order; a bad input is a `Failed`
    with its one-line message; `meanwhile` runs while the workers read."""
    motion = Motion(seed=4)
    good = [write_motive(tmp_path / f"g{i}.csv", motion, T, seed=i) for i in range(2)]
    paths = [good[0], tmp_path / "missing.csv", good[1]]
    ran = []
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        out = _workers.run_all(read_raw, [((p,), {"body": "DelFly"}) for p in paths], pool,
                               meanwhile=lambda: ran.append(1))
    assert ran == [1]
    assert _workers.run_all(read_raw, [((good[0],), {"body": "DelFly"})],
                            meanwhile=lambda: ran.append(2))[0].name == "g0"
    assert ran == [1]  # nothing meanwhile without workers
    assert isinstance(out[1], _workers.Failed) and "missing.csv: no such file" in out[1].message
    for p, take in zip(good, (out[0], out[2])):
        ref = read_raw(p, body="DelFly")
        assert take.name == ref.name
        np.testing.assert_array_equal(take.quat, ref.quat)
        np.testing.assert_array_equal(take.onboard.columns["q"], ref.onboard.columns["q"])


def test_no_workers_once_jax_runs_or_for_few_takes():
    import jax  # noqa: F401  (imported by the other tests anyway)

    assert _workers.start(16) is None  # forking a process that runs JAX is not safe
    assert _workers.start(2, processes=None) is None or _workers.cores() < 2


def test_command_on_workers_equals_one_process(tmp_path):
    """`fwid reconstruct` as a process (workers forked: 4 takes) writes the same flights and
    `reconstruction.json` as `fwid.reconstruct` in this process (no workers); the take
    with a cell that is not a number fails alone."""
    motion = Motion(seed=5)
    raw = tmp_path / "raw"
    raw.mkdir()
    for i in range(3):
        write_motive(raw / f"m{i}.csv", motion, T, seed=10 + i, offset=-7.31 + i)
    bad = write_motive(raw / "bad.csv", motion, T, seed=20)
    lines = bad.read_text().splitlines()
    lines[100] = lines[100].replace(",", ",x", 1)  # a cell that is not a number
    bad.write_text("\n".join(lines) + "\n")
    res = fwid.reconstruct(raw, body="DelFly")
    assert [Path(p).name for p, _ in res.failures] == ["bad.csv"]
    fwid.write_reconstruction(res, tmp_path / "here")
    proc = subprocess.run([sys.executable, "-m", "fwid.cli", "reconstruct", str(raw), "--out",
                           str(tmp_path / "there"), "--body", "DelFly"], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert "bad.csv" in proc.stderr and "not a number" in proc.stderr
    assert "warn" not in proc.stderr.lower(), proc.stderr  # no fork warning from JAX
    for i in range(3):
        here = (tmp_path / "here" / f"m{i}.csv").read_text()
        assert (tmp_path / "there" / f"m{i}.csv").read_text() == here
        assert (tmp_path / "there" / f"m{i}.reconstruction.png").stat().st_size > 10_000
    rep = [json.loads((tmp_path / d / "reconstruction.json").read_text()) for d in ("here", "there")]
    assert rep[0] == rep[1] and len(rep[0]["flights"]) == 3
