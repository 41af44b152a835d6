"""Flights spread over devices: the counts, and that the spread fit equals the plain one."""

import jax
import numpy as np
import pytest

import fwid
from fwid.estimate import _devices


@pytest.mark.parametrize("devices, flights, padded, spread", [
    (1, 5, 5, False), (2, 1, 1, False), (2, 3, 4, False), (2, 4, 4, True), (4, 6, 8, False),
    (4, 8, 8, True),
])
def test_counts_and_mesh(monkeypatch, devices, flights, padded, spread):
    monkeypatch.setattr(_devices, "device_count", lambda: devices)
    assert _devices.padded_count(flights) == padded
    if devices > len(jax.devices()):  # a mesh needs the devices to exist
        return
    assert (_devices.flight_mesh(flights) is not None) == spread


def test_import_gives_one_cpu_device_per_core():
    """`import fwid` (done by the test session before any JAX work) asks for one CPU device
    per core, at most 8, unless FWID_CPU_DEVICES or XLA_FLAGS chose otherwise."""
    import os

    if os.environ.get("FWID_CPU_DEVICES") or "device_count" in os.environ.get("XLA_FLAGS", ""):
        pytest.skip("the device count was chosen from outside")
    if jax.default_backend() != "cpu":
        pytest.skip("not a CPU backend")
    cores = len(os.sched_getaffinity(0))
    assert len(jax.devices()) == min(cores, 8)


def test_spread_fit_equals_one_device(monkeypatch, lon_flight):
    """The same flights fitted with the batch split over the devices (shard_map) and on one
    device (plain vmap): identical to 1e-12."""
    if len(jax.devices()) < 2:
        pytest.skip("one device")
    rng = np.random.default_rng(0)
    exps = [lon_flight.experiment(lon_flight.ys + 1e-3 * rng.normal(size=lon_flight.ys.shape))
            for _ in range(2)]
    spread = fwid.fit_each(fwid.longitudinal(), exps)
    import fwid.estimate._each as oe  # where fit_each lives

    assert oe.flight_mesh(2) is not None
    monkeypatch.setattr(oe, "flight_mesh", lambda n: None)  # (the mesh is a static argument)
    plain = fwid.fit_each(fwid.longitudinal(), exps)
    for a, b in zip(spread, plain):
        np.testing.assert_allclose(np.asarray(a.theta), np.asarray(b.theta), rtol=1e-12)


@pytest.mark.parametrize("params, per", [(16, 24), (30, 3), (60, 1), (4, 1562)])
def test_flights_per_call_keeps_lapack_batches_below_the_split(params, per):
    """Batched p x p solves of `per` flights cost below half of jaxlib's split threshold
    (beyond which 128 flights of 16 parameters on 2 CPU devices hung), and at least one
    flight is always allowed."""
    if jax.default_backend() != "cpu":
        assert _devices.flights_per_call(params) is None
        return
    got = _devices.flights_per_call(params)
    assert got == per
    assert got == 1 or got * params ** 3 <= _devices.LAPACK_SPLIT_FLOPS // 2


def test_fit_in_several_calls_equals_one_call(monkeypatch, lon_flight):
    """Five flights fitted in balanced calls of at most one flight per device (as many
    flights would be) give the estimates of the single call to 1e-12, in the flights'
    order."""
    import fwid.estimate._each as oe

    rng = np.random.default_rng(1)
    exps = [lon_flight.experiment(lon_flight.ys + 1e-3 * rng.normal(size=lon_flight.ys.shape))
            for _ in range(5)]
    model = fwid.longitudinal()
    one = fwid.fit_each(model, exps)
    calls = []
    run_call = oe._run_call
    monkeypatch.setattr(oe, "flights_per_call", lambda p: 1)
    monkeypatch.setattr(oe, "_run_call", lambda *a: calls.append(len(a[1])) or run_call(*a))
    several = fwid.fit_each(model, exps)
    assert len(calls) >= 2 and sum(calls) == 5
    for a, b in zip(one, several):
        np.testing.assert_allclose(np.asarray(a.theta), np.asarray(b.theta), rtol=1e-12)
