"""fwid: identify the flight dynamics of flapping-wing micro air vehicles from free-flight data.

Importing fwid (JAX, once it is imported) turns on JAX's 64-bit mode (`jax_enable_x64`): output-error estimation needs
float64 (Gauss-Newton with tight tolerances never terminates in float32). Set the environment
variable `FWID_NO_X64=1` to keep JAX's default and manage the precision yourself.

It also gives JAX one CPU device per CPU core available to the process (`jax_num_cpu_devices`,
at most 8), so that `fwid.fit_each` and joint fits spread their flights over the cores; JAX's
default is one CPU device, on which XLA runs each flight loop on one core. This only happens
when JAX has run nothing yet and nobody chose a count (`jax_num_cpu_devices`, or
`--xla_force_host_platform_device_count` in `XLA_FLAGS`); `FWID_CPU_DEVICES=N` sets N
(`FWID_CPU_DEVICES=1`: leave JAX's default). Computations that are not spread run on the first
device as before.

`import fwid` itself is light: JAX, diffrax and matplotlib are imported when first needed (a
name of `fwid` is looked up in its stage's package on first use: `fwid.fit` imports
`fwid.estimate`), so `fwid --help` answers without them. JAX is set up right after its first
import, wherever it happens (`fwid._jax_setup.on_jax_import`); fwid also keeps compiled
programs in a per-user cache folder (`FWID_JAX_CACHE`; the guide's page 'The command line',
'Compilation cache').
"""

import importlib
from importlib.metadata import PackageNotFoundError as _NotInstalled
from importlib.metadata import version as _version

from ._errors import (
    ExcitationError as ExcitationError,
    FitDivergedError as FitDivergedError,
    DiagnosisWarning as DiagnosisWarning,
    FitWarning as FitWarning,
    FlightDataError as FlightDataError,
    FwidError as FwidError,
    InputError as InputError,
)
from ._jax_setup import on_jax_import as _on_jax_import


def _own_version() -> str:
    """The installed distribution's version; from a source checkout that is not installed
    (on `PYTHONPATH`), the `version` line of its `pyproject.toml`."""
    try:
        return _version("fwid")
    except _NotInstalled:
        import re
        from pathlib import Path

        toml = Path(__file__).resolve().parents[1] / "pyproject.toml"
        found = re.search(r'^version\s*=\s*"([^"]+)"', toml.read_text(), re.M) \
            if toml.is_file() else None
        return found.group(1) if found else "0+unknown"


__version__ = _own_version()

_on_jax_import()

#: The public names, by the stage (subpackage) that defines them; imported on first use.
EXPORTS = {
    "data": (
        "Flight", "Vehicle", "estimate_trim", "first_input_index", "load_flight", "load_flights",
        "load_vehicle",
    ),
    "reconstruction": (
        "read_map", "read_raw", "reconstruct", "write_reconstruction",
    ),
    "decomposition": (
        "Decomposition", "check_flapping_frequency", "cycle_averaged", "decompose",
        "estimate_flapping_frequency", "flapping_part", "flapping_phase", "highpass", "lowpass",
    ),
    "models": (
        "GreyBoxModel", "combined", "estimate_phase_offset", "force_parts", "fourier_model",
        "fourier_series", "shift_phase", "heading_rate", "lateral", "longitudinal",
    ),
    "simulation": (
        "RK4", "Experiment", "experiment", "simulate", "simulate_forces", "stack_experiments",
        "unstack_experiments",
    ),
    "estimate": (
        "RelaxedGaussNewton", "FitResult", "fit", "fit_each", "least_squares_start",
        "fit_shooting", "fit_filter_error", "FilterErrorResult", "steady_state_gain",
        "initialize_distributed", "prior_from", "prior_information",
    ),
    "diagnosis": (
        "CATALOGUE", "Diagnosis", "diagnose", "read_reconstruction",
    ),
    "validate": (
        "StateSpace", "eigenvalues", "state_space", "fit_metrics", "modes",
    ),
    "sensitivity": (
        "cutoff_cost", "eigenvalue_sensitivity", "estimate_sensitivity_to_cutoff",
        "metric_sensitivity", "output_sensitivity", "rank_sensitivities",
    ),
    "design": (
        "Design", "Discrimination", "design_discriminating", "design_input",
    ),
    "identification": (
        "CombinedIdentification", "FlappingIdentification", "FlightFit", "Identification",
        "JointComparison", "SteadyVsManoeuvre", "compare_joint", "evaluate", "identify",
        "identify_combined", "identify_flapping_model", "steady_vs_manoeuvre",
    ),
    "report": (
        "harmonic_amplitudes", "plot_steady_vs_manoeuvre", "plot_superposition",
        "plot_time_and_spectrum", "identification_report", "plot_decomposition",
        "plot_flight_fit", "plot_poles", "plot_reconstruction", "write_json",
    ),
}
_STAGE = {name: stage for stage, names in EXPORTS.items() for name in names}
_SUBPACKAGES = (*EXPORTS, "synth", "cli")
__all__ = ["__version__", "DiagnosisWarning", "ExcitationError", "FitDivergedError", "FitWarning",
           "FlightDataError", "FwidError", "InputError", *_STAGE]


def __getattr__(name):
    if name in _STAGE:
        value = getattr(importlib.import_module(f".{_STAGE[name]}", __name__), name)
        globals()[name] = value
        return value
    if name in _SUBPACKAGES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted({*globals(), *__all__, *_SUBPACKAGES})

