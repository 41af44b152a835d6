"""What the pipelines found, for people and for programs (the report format).

The JSON reports that the command line writes (`report.json`, `diagnosis.json`; their keys are
listed in the guide's page "Formats and interfaces"), written whole or not at all by
[`fwid.write_json`][], with [`fwid.identification_report`][] building `report.json`'s content
from an identification; and the figures, drawn with object-oriented matplotlib (each function
returns a `Figure` and, given a path, saves it): the fits and poles
([`fwid.plot_flight_fit`][], [`fwid.plot_poles`][], Figures 6-11 of the paper), the split
([`fwid.plot_decomposition`][], Figure 4), time and spectrum of the flapping forces
([`fwid.plot_time_and_spectrum`][], [`fwid.plot_steady_vs_manoeuvre`][],
[`fwid.plot_superposition`][], Figures 12-17) and a reconstructed take
([`fwid.plot_reconstruction`][]).

The modules:

- JSON reports (`report.json`, `diagnosis.json`), written whole or not at all:
  [`fwid.write_json`][] (`_json.py`); [`fwid.identification_report`][] (`_identification.py`,
  `--model lon|lat`, and the blocks the other reports share); `flapping_report`,
  `combined_report` (`_flapping.py`, `--model flap|combined`); `joint_report` (`_joint.py`,
  `joint_vs_individual`).
- Terminal summaries: `identification_summary`, `flapping_summary` and the tables
  (`_table.py`); `joint_summary` (`_joint.py`); `diagnosis_summary` (`_diagnosis.py`).
- Figures (object-oriented matplotlib): fits and poles (`_figures.py`, Figures 6-11), a batch's
  fits in one figure (`_overview.py`, `plot_fits_overview`), the
  decomposition (`_decomposition_plot.py`, Figure 4), a reconstructed take
  (`_reconstruction.py`, `plot_reconstruction`), time and spectrum (`_spectra.py`,
  Figures 12-17), the gap map (`_diagnosis.py`).

Submodules are imported on first use of one of their names (PEP 562): `fwid identify` does
not pay for the diagnosis's figures, nor the diagnosis for the flapping plots.
"""

import importlib

#: The public names, by the submodule that defines them.
EXPORTS = {
    "_decomposition_plot": (
        "plot_decomposition",
    ),
    "_diagnosis": (
        "diagnosis_summary", "plot_gap_map", "plot_gap_sim", "write_diagnosis",
    ),
    "_failure": (
        "failure_reason",
    ),
    "_figures": (
        "plot_flight_fit", "plot_poles",
    ),
    "_overview": (
        "plot_fits_overview",
    ),
    "_flapping": (
        "combined_report", "flapping_report",
    ),
    "_identification": (
        "converged_flags", "identification_report", "modes_spread", "pooled_metrics",
    ),
    "_joint": (
        "joint_report", "joint_summary",
    ),
    "_json": (
        "parameters_csv", "write_json", "write_text",
    ),
    "_reconstruction": (
        "plot_reconstruction",
    ),
    "_spectra": (
        "amplitude_spectrum", "harmonic_amplitudes", "peak_table", "plot_steady_vs_manoeuvre",
        "plot_superposition", "plot_time_and_spectrum",
    ),
    "_table": (
        "flapping_summary", "identification_summary", "metrics_table", "modes_table",
        "parameter_table", "spread_table",
    ),
}
_MODULE = {name: mod for mod, names in EXPORTS.items() for name in names}
__all__ = list(_MODULE)


def __getattr__(name: str):
    if name in _MODULE:
        value = getattr(importlib.import_module(f".{_MODULE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_MODULE))
