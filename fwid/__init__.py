"""fwid: identify the flight dynamics of flapping-wing micro air vehicles from free-flight data.

Importing fwid turns on JAX's 64-bit mode (`jax_enable_x64`): output-error estimation needs
float64 (Gauss-Newton with tight tolerances never terminates in float32). Set the environment
variable `FWID_NO_X64=1` to keep JAX's default and manage the precision yourself.

It also gives JAX one CPU device per CPU core available to the process (`jax_num_cpu_devices`,
at most 8), so that `fwid.fit_each` and joint fits spread their flights over the cores; JAX's
default is one CPU device, on which XLA runs each flight loop on one core. This only happens
when JAX has run nothing yet and nobody chose a count (`jax_num_cpu_devices`, or
`--xla_force_host_platform_device_count` in `XLA_FLAGS`); `FWID_CPU_DEVICES=N` sets N
(`FWID_CPU_DEVICES=1`: leave JAX's default). Computations that are not spread run on the first
device as before.
"""

from ._jax_setup import cpu_devices as _cpu_devices, enable_x64 as _enable_x64

_enable_x64()
_cpu_devices()

from ._errors import (
    ExcitationError as ExcitationError,
    FitDivergedError as FitDivergedError,
    FitWarning as FitWarning,
    FlightDataError as FlightDataError,
    FwidError as FwidError,
    InputError as InputError,
)

__version__ = "0.1.0"

from .data import (
    Flight as Flight,
    Vehicle as Vehicle,
    estimate_trim as estimate_trim,
    first_input_index as first_input_index,
    load_flight as load_flight,
    load_flights as load_flights,
    load_vehicle as load_vehicle,
)
from .decompose import (
    Decomposition as Decomposition,
    check_flapping_frequency as check_flapping_frequency,
    cycle_averaged as cycle_averaged,
    decompose as decompose,
    estimate_flapping_frequency as estimate_flapping_frequency,
    flapping_part as flapping_part,
    flapping_phase as flapping_phase,
    highpass as highpass,
    lowpass as lowpass,
)
from .models import (
    GreyBoxModel as GreyBoxModel,
    combined as combined,
    estimate_phase_offset as estimate_phase_offset,
    force_parts as force_parts,
    fourier_model as fourier_model,
    fourier_series as fourier_series,
    shift_phase as shift_phase,
    heading_rate as heading_rate,
    lateral as lateral,
    longitudinal as longitudinal,
)
from .simulate import (
    RK4 as RK4,
    Experiment as Experiment,
    experiment as experiment,
    simulate as simulate,
    simulate_forces as simulate_forces,
    stack_experiments as stack_experiments,
    unstack_experiments as unstack_experiments,
)
from .estimate import (
    RelaxedGaussNewton as RelaxedGaussNewton,
    FitResult as FitResult,
    fit as fit,
    fit_each as fit_each,
    least_squares_start as least_squares_start,
)
from .diagnose import (
    CATALOGUE as CATALOGUE,
    Diagnosis as Diagnosis,
    diagnose as diagnose,
)
from .validate import (
    StateSpace as StateSpace,
    eigenvalues as eigenvalues,
    state_space as state_space,
    fit_metrics as fit_metrics,
    modes as modes,
)
from .sensitivity import (
    cutoff_cost as cutoff_cost,
    eigenvalue_sensitivity as eigenvalue_sensitivity,
    estimate_sensitivity_to_cutoff as estimate_sensitivity_to_cutoff,
    metric_sensitivity as metric_sensitivity,
    output_sensitivity as output_sensitivity,
    rank_sensitivities as rank_sensitivities,
)
from .identify import (
    CombinedIdentification as CombinedIdentification,
    FlappingIdentification as FlappingIdentification,
    FlightFit as FlightFit,
    Identification as Identification,
    JointComparison as JointComparison,
    SteadyVsManoeuvre as SteadyVsManoeuvre,
    compare_joint as compare_joint,
    evaluate as evaluate,
    identify as identify,
    identify_combined as identify_combined,
    identify_flapping_model as identify_flapping_model,
    steady_vs_manoeuvre as steady_vs_manoeuvre,
)
from .report import (
    harmonic_amplitudes as harmonic_amplitudes,
    plot_steady_vs_manoeuvre as plot_steady_vs_manoeuvre,
    plot_superposition as plot_superposition,
    plot_time_and_spectrum as plot_time_and_spectrum,
    identification_report as identification_report,
    plot_decomposition as plot_decomposition,
    plot_flight_fit as plot_flight_fit,
    plot_poles as plot_poles,
    write_json as write_json,
)
