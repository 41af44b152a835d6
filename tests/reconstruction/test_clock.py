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


def test_std_is_no_better_than_the_tracking_allows():
    """With the attitude's noise given, the offset's `std` is at least the Cramer-Rao bound of
    a time shift seen through that noise, `1 / sqrt(sum w^2 / sigma^2)`; without it, only the
    fit's curvature (far smaller: it takes the smoothed rates as exact)."""
    t = np.arange(901) * 0.005
    offset = 3.25
    t_log = t[0] - offset - 0.1 + np.arange(2400) * 0.001953125
    gyro = _rates(t_log + offset)
    w = _rates(t) + 0.002 * np.random.default_rng(0).standard_normal((len(t), 3))
    sigma = np.full(3, np.deg2rad(0.15))
    bound = 1.0 / np.sqrt(np.sum(w ** 2 / sigma ** 2))
    alone = find_offset(t, w, t_log, gyro, 12.0)
    told = find_offset(t, w, t_log, gyro, 12.0, sigma=sigma)
    assert told.offset == alone.offset
    assert told.std >= bound and told.std >= alone.std
    assert alone.std < 0.5 * bound
