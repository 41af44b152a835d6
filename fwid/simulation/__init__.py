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
