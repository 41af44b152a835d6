"""The time base from frame numbers: uniform whatever the time column's rounding; missing
frames are rows to bridge, a long run of them refused naming the frames; a time column that
departs from the frames beyond its rounding is said."""

import numpy as np
import pytest

from fwid import FlightDataError
from fwid.reconstruction._frames import frame_times

RATE = 120.0


def test_millisecond_time_column_gives_frames_over_rate():
    frames = np.arange(0, 1200.0)
    time = np.floor(frames / RATE * 1e3) / 1e3  # 0.008, 0.016, 0.025, 0.033 ...
    ft = frame_times(frames, time, RATE, "take.csv", 8, 0.1)
    assert np.allclose(np.diff(ft.t), 1 / RATE, rtol=0, atol=1e-12)
    assert ft.t[0] == 0.0 and np.array_equal(ft.rows, np.arange(1200))
    assert ft.missing.size == 0 and ft.warnings == []


def test_missing_frames_become_rows_to_bridge():
    frames = np.delete(np.arange(100, 400.0), [50, 51, 52, 200])  # frames 150-152 and 300
    time = frames / RATE
    ft = frame_times(frames, time, RATE, "take.csv", 8, 0.1)
    assert len(ft.t) == 300 and np.isclose(ft.t[0], 100 / RATE)
    assert np.array_equal(ft.missing, [50, 51, 52, 200])
    assert np.allclose(ft.t[ft.rows], time)
    assert ft.warnings == ["4 frames missing from the export (first frame 150, t = 1.25 s): "
                           "bridged as dropouts"]


def test_a_long_run_of_missing_frames_is_refused_naming_it():
    frames = np.concatenate([np.arange(0, 100.0), np.arange(130, 300.0)])
    with pytest.raises(FlightDataError) as e:
        frame_times(frames, frames / RATE, RATE, "take.csv", 8, 0.1)
    msg = str(e.value)
    assert msg.startswith("take.csv, line 108: frames 100 to 129 (t = 0.833333 to 1.075 s, "
                          "0.25 s) are missing from the export")
    assert "--max-dropout" in msg and "cut the take" in msg and "\n" not in msg


def test_time_column_off_the_frames_is_a_warning():
    frames = np.arange(0, 600.0)
    time = frames / 119.0  # the header's rate is not the one the time column was written at
    ft = frame_times(frames, time, RATE, "take.csv", 8, 0.1)
    assert np.allclose(np.diff(ft.t), 1 / RATE)
    assert len(ft.warnings) == 1 and ft.warnings[0].startswith(
        "the Time (Seconds) column departs from Frame / 120 Hz by up to 41.9 ms (frame 599, "
        "line 607)")


@pytest.mark.parametrize("frames, words", [
    ([0, 1, 2, 2, 3], "line 11: frame 2 follows frame 2"),
    ([0, 1, 2.5, 3], "line 10: the frame number 2.5 is not a whole number"),
])
def test_bad_frame_numbers_are_refused(frames, words):
    frames = np.asarray(frames, float)
    with pytest.raises(FlightDataError, match=words):
        frame_times(frames, frames / RATE, RATE, "take.csv", 8, 0.1)
