"""Synthetic flights for the tests of `fwid.data`: simple signals written as CSV files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

LON_TRIM = {"u": 0.6, "w": 0.25, "theta": 1.25, "q": 0.0, "de": 0.05, "f": 12.5}
LAT_TRIM = {"v": 0.02, "p": 0.0, "r": 0.0, "phi": 0.03, "psi": 0.4, "dr": -0.04}
VEHICLE = {"mass": 0.018, "Ix": 1.2e-5, "Iy": 1.5e-5, "Iz": 8.0e-6, "Ixz": 1.0e-7, "g": 9.81}


def doublet(t, t0=1.0, half=0.5, amp=0.05):
    """+amp for `half` seconds from `t0`, then -amp for `half` seconds, else 0."""
    return amp * (((t >= t0) & (t < t0 + half)) * 1.0 - ((t >= t0 + half) & (t < t0 + 2 * half)))


def step(t, t0=1.0, amp=0.05):
    return amp * (t >= t0)


def input_211(t, t0=1.0, unit=0.2, amp=0.05):
    """The 3-2-1-1 family's '2-1-1': +amp for 2 units, -amp for 1, +amp for 1."""
    x = np.zeros_like(t)
    x[(t >= t0) & (t < t0 + 2 * unit)] = amp
    x[(t >= t0 + 2 * unit) & (t < t0 + 3 * unit)] = -amp
    x[(t >= t0 + 3 * unit) & (t < t0 + 4 * unit)] = amp
    return x


def _response(t, u_in, tau=0.15, gain=1.0):
    """First-order lag of the input (zero before the input starts)."""
    dt = t[1] - t[0]
    a = dt / (tau + dt)
    y = np.zeros_like(u_in)
    for k in range(1, len(t)):
        y[k] = y[k - 1] + a * (gain * u_in[k] - y[k - 1])
    return y


def lon_flight(
    duration=4.0,
    rate=200.0,
    t_input=1.0,
    amp=0.05,
    ripple=0.02,
    f_flap=12.0,
    noise=0.002,
    shape="doublet",
    seed=0,
):
    """A longitudinal flight: trim `LON_TRIM`, an elevator `shape` input at `t_input` with
    a flapping ripple on `de`, first-order responses of the states. Returns `{col: array}`."""
    rng = np.random.default_rng(seed)
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    make = {"doublet": doublet, "step": step, "211": input_211}[shape]
    u_in = make(t, t_input, amp=amp)
    cols = {"t": t}
    cols["de"] = (
        LON_TRIM["de"]
        + u_in
        + ripple * np.sin(2 * np.pi * f_flap * t + 0.7)
        + noise * rng.standard_normal(n)
    )
    resp = _response(t, u_in)
    for c, g in (("q", -8.0), ("u", 0.5), ("w", -1.5), ("theta", -2.0)):
        cols[c] = LON_TRIM[c] + g * resp + noise * rng.standard_normal(n)
    cols["f"] = LON_TRIM["f"] + 0.1 * np.sin(2 * np.pi * 0.3 * t)
    cols["X"] = -0.01 + 0.002 * np.sin(2 * np.pi * f_flap * t)
    cols["Z"] = -0.17 + 0.02 * np.sin(2 * np.pi * f_flap * t)
    cols["M"] = 1e-4 * np.sin(2 * np.pi * f_flap * t)
    return cols


def lat_flight(duration=4.0, rate=200.0, t_input=1.5, amp=0.08, ripple=0.02, noise=0.002, seed=1):
    """A lateral flight: a rudder doublet at `t_input`; the elevator only ripples."""
    rng = np.random.default_rng(seed)
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    u_in = doublet(t, t_input, amp=amp)
    cols = {"t": t}
    cols["dr"] = LAT_TRIM["dr"] + u_in + 0.003 * rng.standard_normal(n)
    cols["de"] = 0.05 + ripple * np.sin(2 * np.pi * 12.0 * t) + noise * rng.standard_normal(n)
    resp = _response(t, u_in)
    for c, g in (("v", 0.4), ("p", 3.0), ("r", -5.0), ("phi", 1.0), ("psi", 0.5)):
        cols[c] = LAT_TRIM[c] + g * resp + noise * rng.standard_normal(n)
    return cols


def write_csv(path, cols, fmt="%.10g"):
    """Write `{col: array}` as a CSV with a header row; returns the path."""
    path = Path(path)
    names = list(cols)
    data = np.column_stack([np.asarray(cols[c], dtype=float) for c in names])
    np.savetxt(path, data, fmt=fmt, delimiter=",", header=",".join(names), comments="")
    return path


def write_flight(folder, name="lon_0.csv", cols=None, vehicle=True, sidecar=None, **kw):
    """Write a flight `name` into `folder` (default: `lon_flight(**kw)`), with `vehicle.json`
    beside it (`vehicle=True`: `VEHICLE`; a dict: that) and an optional sidecar dict."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = write_csv(folder / name, lon_flight(**kw) if cols is None else cols)
    if vehicle:
        write_json(folder / "vehicle.json", VEHICLE if vehicle is True else vehicle)
    if sidecar is not None:
        write_json(path.with_suffix(".json"), sidecar)
    return path


def write_json(path, obj):
    Path(path).write_text(json.dumps(obj))
    return Path(path)


def write_text(path, text):
    Path(path).write_text(text)
    return Path(path)
