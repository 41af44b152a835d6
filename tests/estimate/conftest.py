"""Simulated DelFly flights shared by the estimation tests (noise-free truth from fwid).

The true parameters differ from the models' nominal values (Tables 1 and 4 scaled by
0.7-1.3 and non-zero biases), so a start that did nothing could not pass.
"""

import numpy as np
import pytest

import fwid  # noqa: F401  (float64)
from fwid.models import TABLE1, TABLE4, lateral, longitudinal
from fwid.simulation import Experiment, simulate, simulate_forces

DT = 0.005
N = 901  # 4.5 s at 200 Hz
T = np.arange(N) * DT

LON_CONSTS = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
LAT_CONSTS = dict(mass=0.0205, Ix=8e-5, Iz=3e-5, Ixz=1e-6, g=9.81, u0=0.3, w0=0.6, theta0=1.2)

_LON_FACTORS = (1.08, 1.24, 1.17, 0.84, 0.88, 1.22, 0.70, 1.19, 1.18, 0.98, 0.88, 0.87)
_LAT_FACTORS = (0.85, 0.97, 1.10, 1.03, 1.30, 1.18, 1.07, 1.29, 0.83, 0.80, 1.07, 0.73)
LON_TRUE = {k: v * f for (k, v), f in zip(TABLE1.items(), _LON_FACTORS)}
LON_TRUE.update(bq=0.02, bu=-0.01, bw=0.015, btheta=-0.005)
LAT_TRUE = {k: v * f for (k, v), f in zip(TABLE4.items(), _LAT_FACTORS)}
LAT_TRUE.update(bp=0.01, br=-0.02, bv=0.005, bphi=0.003)

LON_BIASES = ("bq", "bu", "bw", "btheta")
LAT_BIASES = ("bp", "br", "bv", "bphi")


def input_3211(t, t0=0.5, unit=0.3, amp=0.05):
    u = np.zeros_like(t)
    edges, signs = (0, 3, 5, 6, 7), (1, -1, 1, -1)
    for k, s in enumerate(signs):
        u[(t >= t0 + edges[k] * unit) & (t < t0 + edges[k + 1] * unit)] = s * amp
    return u


def input_doublet(t, t0=0.5, half=0.4, amp=0.1):
    u = np.zeros_like(t)
    u[(t >= t0) & (t < t0 + half)] = amp
    u[(t >= t0 + half) & (t < t0 + 2 * half)] = -amp
    return u


class Flight:
    """A noise-free simulated flight: the true model, its states/outputs, an Experiment."""

    def __init__(self, model, u, consts):
        self.model = model
        self.consts = consts
        self.t = T
        self.u = u
        self.x0 = np.zeros(len(model.states))
        xs, ys = simulate(model, Experiment(T, u, np.zeros((N, len(model.outputs))), self.x0,
                                            consts))
        self.xs = np.asarray(xs)
        self.ys = np.asarray(ys)
        self.forces = np.asarray(simulate_forces(model, xs, Experiment(T, u, ys, self.x0, consts)))
        self.theta = np.asarray(model.theta())
        self.names = model.free

    def experiment(self, z=None, *, forces=False, consts=None, u=None):
        return Experiment(self.t, self.u if u is None else u, self.ys if z is None else z,
                          self.x0, self.consts if consts is None else consts,
                          forces=self.forces if forces else None)


def make_flight(kind: str, u=None) -> Flight:
    """The true longitudinal ("lon", 3211 elevator) or lateral ("lat", rudder doublet)
    flight; `u` replaces the input."""
    if kind == "lon":
        return Flight(longitudinal(LON_TRUE), input_3211(T) if u is None else u, LON_CONSTS)
    return Flight(lateral(LAT_TRUE), input_doublet(T) if u is None else u, LAT_CONSTS)


@pytest.fixture(scope="session")
def flight_factory():
    """`make_flight` as a fixture (test modules do not import this conftest)."""
    return make_flight


@pytest.fixture(scope="session")
def lon_flight():
    return make_flight("lon")


@pytest.fixture(scope="session")
def lat_flight():
    return make_flight("lat")
