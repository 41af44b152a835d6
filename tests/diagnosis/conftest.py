"""Simulated flights with a withheld effect, written once per session."""

import numpy as np
import pytest

from fwid.synth import write_flights


@pytest.fixture(scope="session")
def effect_flights(tmp_path_factory):
    """`effect_flights(effect, axis="lon", strength=1.0, seed=0, n_train=8, n_test=8,
    form=None)` ->
    `(train_dir, test_dir)`; sidecars are deleted (the diagnosis sees CSV columns only)."""
    cache = {}

    def make(effect, axis="lon", strength=1.0, seed=0, n_train=8, n_test=8, form=None):
        key = (effect, axis, strength, seed, n_train, n_test, form)
        if key not in cache:
            root = tmp_path_factory.mktemp(f"{effect}-{axis}")
            for part, n, s in (("train", n_train, 100 * seed), ("test", n_test, 100 * seed + 50)):
                for p in write_flights(root / part, n, axis, seed=s, effect=effect,
                                       strength=strength,
                                       **({"form": form} if form else {})):
                    p.with_suffix(".json").unlink()
            cache[key] = (root / "train", root / "test")
        return cache[key]

    return make


def resample(src, dst, rate: float, cut: float = 0.0):
    """Copy a folder of flights to `dst`, linearly resampled to `rate` Hz and `cut` s shorter."""
    dst.mkdir(parents=True, exist_ok=True)
    (dst / "vehicle.json").write_text((src / "vehicle.json").read_text())
    for csv in sorted(src.glob("*.csv")):
        header = csv.read_text().splitlines()[0]
        data = np.loadtxt(csv, delimiter=",", skiprows=1)
        t = data[:, 0]
        tn = np.arange(0.0, t[-1] - cut + 1e-12, 1.0 / rate)
        out = np.column_stack([tn] + [np.interp(tn, t, data[:, j]) for j in range(1, data.shape[1])])
        np.savetxt(dst / csv.name, out, delimiter=",", header=header, comments="", fmt="%.12g")
    return dst
