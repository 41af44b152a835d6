"""The flapping frequency from the pose's ripple: the fundamental, not its harmonic."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fwid.reconstruction._ripple import flapping_frequency

FS, F = 200.0, 15.0


def _take(a1: float, a2: float, duration: float = 4.5, seed: int = 0):
    """A pitching/rolling ripple of `a1` deg at F and `a2` deg at 2F, 0.15 deg pose noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / FS)
    th = np.deg2rad(a1 * np.sin(2 * np.pi * F * t) + a2 * np.sin(4 * np.pi * F * t + 0.3))
    noise = np.deg2rad(0.15) * rng.standard_normal((t.size, 3))
    rv = np.column_stack([0.3 * th, th, 0 * th]) + noise
    quat = Rotation.from_rotvec(rv).as_quat()[:, [3, 0, 1, 2]]
    return t, quat, np.ones(t.size, bool)


@pytest.mark.parametrize("a1, a2", [(0.3, 0.9), (0.1, 0.3), (1.0, 0.0)])
def test_the_fundamental_not_its_second_harmonic(a1, a2):
    f, note = flapping_frequency(*_take(a1, a2))
    assert f is not None, note
    assert abs(np.median(f) - F) < 0.2, note
    assert "ripple" in note and "edge" not in note


def test_a_single_line_is_read_where_it_is():
    f, note = flapping_frequency(*_take(0.0, 1.0))
    assert abs(np.median(f) - 2 * F) < 0.2, note


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_noise_only_gives_a_warning_not_a_frequency(seed):
    f, note = flapping_frequency(*_take(0.0, 0.0, seed=seed))
    assert f is None
    assert note.startswith("no flapping line") and "between 5 and 60 Hz" in note
