"""What the pipelines found, for people and for programs (CONTRACTS section 3).

- JSON reports (`report.json`, `diagnosis.json`), written whole or not at all:
  [`fwid.write_json`][] (`_json.py`); [`fwid.identification_report`][] (`_identification.py`,
  `--model lon|lat`, and the blocks the other reports share); `flapping_report`,
  `combined_report` (`_flapping.py`, `--model flap|combined`); `joint_report` (`_joint.py`,
  `joint_vs_individual`).
- Terminal summaries: `identification_summary`, `flapping_summary` and the tables
  (`_table.py`); `joint_summary` (`_joint.py`); `diagnosis_summary` (`_diagnosis.py`).
- Figures (object-oriented matplotlib): fits and poles (`_figures.py`, Figures 6-11), a batch's fits in
  one figure (`_overview.py`, `plot_fits_overview`), the
  decomposition (`_decomposition_plot.py`, Figure 4), time and spectrum (`_spectra.py`,
  Figures 12-17), the gap map (`_diagnosis.py`).
"""

from ._decomposition_plot import plot_decomposition as plot_decomposition
from ._diagnosis import (
    diagnosis_summary as diagnosis_summary,
    plot_gap_map as plot_gap_map,
    plot_gap_sim as plot_gap_sim,
    write_diagnosis as write_diagnosis,
)
from ._figures import plot_flight_fit as plot_flight_fit, plot_poles as plot_poles
from ._overview import plot_fits_overview as plot_fits_overview
from ._flapping import combined_report as combined_report, flapping_report as flapping_report
from ._identification import (
    converged_flags as converged_flags,
    identification_report as identification_report,
    modes_spread as modes_spread,
    pooled_metrics as pooled_metrics,
)
from ._joint import joint_report as joint_report, joint_summary as joint_summary
from ._json import (
    parameters_csv as parameters_csv,
    write_json as write_json,
    write_text as write_text,
)
from ._spectra import (
    amplitude_spectrum as amplitude_spectrum,
    harmonic_amplitudes as harmonic_amplitudes,
    peak_table as peak_table,
    plot_steady_vs_manoeuvre as plot_steady_vs_manoeuvre,
    plot_superposition as plot_superposition,
    plot_time_and_spectrum as plot_time_and_spectrum,
)
from ._table import (
    flapping_summary as flapping_summary,
    identification_summary as identification_summary,
    metrics_table as metrics_table,
    modes_table as modes_table,
    parameter_table as parameter_table,
    spread_table as spread_table,
)
