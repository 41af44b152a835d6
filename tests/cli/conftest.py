"""Shared fixtures of the command-line tests."""

import pytest

from fwid.cli import main


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    """One short simulated longitudinal flight (2.5 s, seed 4); a module that defines its
    own `flight` uses that instead."""
    out = tmp_path_factory.mktemp("flights")
    assert main(["simulate", str(out), "--flights", "1", "--seed", "4", "--duration", "2.5"]) == 0
    return out / "lon_0.csv"
