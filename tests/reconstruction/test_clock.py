"""The clock offset between the autopilot's log and the take (`_clock.find_offset`)."""

import numpy as np

from fwid.reconstruction._clock import find_offset


def _rates(t):
    """Smooth body rates (rad/s) with a few seconds of manoeuvre."""
    return np.stack([0.3 * np.sin(1.3 * t) + 0.1 * np.sin(4.1 * t + 1.0),
                     0.5 * np.sin(2.2 * t + 0.3) * np.exp(-0.1 * (t - 2) ** 2),
                     0.2 * np.cos(0.9 * t) + 0.05 * np.sin(6.0 * t)], 1)


def test_a_log_whose_grid_ends_past_it_by_round_off_is_aligned():
    """A 512 Hz log whose length is a whole number of take steps (200 Hz): the search grid's
    last point fell 7e-13 s past the log's end, the spline gave NaN there, the low-pass spread
    it over the whole grid and every lag looked like no overlap."""
    t = np.arange(901) * 0.005
    offset = -9.59271754  # t_tracking = t_onboard + offset
    t_log = 9.59271754 + np.arange(2241) * 0.001953125
    dt = (t[-1] - t[0]) / (len(t) - 1)
    assert np.arange(t_log[0], t_log[-1] + 1e-9, dt)[-1] > t_log[-1]  # the case
    gyro = _rates(t_log + offset)
    clock = find_offset(t, _rates(t), t_log, gyro, 12.0)
    assert clock is not None
    assert abs(clock.offset - offset) < 1e-4
