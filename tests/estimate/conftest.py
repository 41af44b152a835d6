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


# -- a small short-period case (Jategaonkar's ATTAS model), for the prior and the bounds ---
def _short_period_f(x, u, p, c):
    import jax.numpy as jnp

    alpha, q = x
    return jnp.stack([p["Z0"] + p["Za"] * alpha + (1 + p["Zq"]) * q + p["Zde"] * u[0],
                      p["M0"] + p["Ma"] * alpha + p["Mq"] * q + p["Mde"] * u[0]])


class ShortPeriod:
    """Two 10 s records of a short-period model with white noise, the plain output-error
    fit of the first, and the fit with Mq held at -2.3 (the reference of a bound there)."""

    def __init__(self):
        import fwid

        self.model = fwid.GreyBoxModel(
            _short_period_f, states=("alpha", "q"), inputs=("de",), name="short-period",
            params=dict(Z0=0.0, Za=-0.5, Zq=0.0, Zde=-0.1, M0=0.0, Ma=-5.0, Mq=-2.0, Mde=-7.0))
        truth = self.model.with_params(Za=-1.4, Zq=-0.05, Zde=-0.15, Ma=-7.0, Mq=-2.5,
                                       Mde=-9.0)
        t = np.arange(0.0, 10.0, 0.04)
        rng = np.random.default_rng(0)
        self.exps = []
        for shift in (1.0, 2.0):  # a doublet on the elevator
            de = 0.02 * (np.sign(np.sin(np.pi * (t - shift))) * ((t > shift) & (t < shift + 2)))
            u = de[:, None]
            _, y = simulate(truth, Experiment(t, u, np.zeros((t.size, 2)), x0=np.zeros(2)))
            z = np.asarray(y) + 1e-3 * rng.normal(size=y.shape)
            self.exps.append(Experiment(t, u, z))
        self.plain = fwid.fit(self.model, self.exps[0])
        self.held_mq = fwid.fit(
            self.model.with_params(Mq=-2.3).with_free([k for k in self.model.free if k != "Mq"]),
            self.exps[0])

    def at(self, result, name):
        return float(np.asarray(result.theta)[result.names.index(name)])

    def std_cr(self, result, name):
        return float(np.asarray(result.std_cr)[result.names.index(name)])


@pytest.fixture(scope="session")
def short_period():
    return ShortPeriod()
