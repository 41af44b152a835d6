"""Simulation: a model's response to a flight's inputs.

An [`fwid.Experiment`][] holds one flight as the estimators see it: the time axis, the inputs,
the measured outputs, the initial state and the flight's constants (trim, mass, inertia);
[`fwid.experiment`][] builds one from a [`fwid.Flight`][]. [`fwid.simulate`][] integrates a
[`fwid.GreyBoxModel`][] over an experiment (by diffrax, with [`fwid.RK4`][], the classical
fixed-step Runge-Kutta of the paper's estimator), [`fwid.simulate_forces`][] gives the model's
loads along the way, and [`fwid.stack_experiments`][] / [`fwid.unstack_experiments`][] pad
flights of different lengths to one and stack them, so that one compiled program serves all.
"""

from ._experiment import (
    Experiment as Experiment,
    experiment as experiment,
    stack_experiments as stack_experiments,
    unstack_experiments as unstack_experiments,
)
from ._simulate import input_at as input_at, simulate as simulate, simulate_forces as simulate_forces
from ._averaged import averaged as averaged
from ._buckets import bucket_length as bucket_length, pad_experiment as pad_experiment
from ._rk4 import RK4 as RK4
