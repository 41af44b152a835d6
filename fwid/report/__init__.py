from ._decomposition_plot import plot_decomposition as plot_decomposition
from ._figures import plot_flight_fit as plot_flight_fit, plot_poles as plot_poles
from ._json import identification_report as identification_report, write_json as write_json
from ._table import (
    identification_summary as identification_summary,
    metrics_table as metrics_table,
    modes_table as modes_table,
    parameter_table as parameter_table,
)
from ._spectra import (
    amplitude_spectrum as amplitude_spectrum,
    harmonic_amplitudes as harmonic_amplitudes,
    peak_table as peak_table,
    plot_steady_vs_manoeuvre as plot_steady_vs_manoeuvre,
    plot_superposition as plot_superposition,
    plot_time_and_spectrum as plot_time_and_spectrum,
)
from ._diagnosis import diagnosis_summary as diagnosis_summary, plot_gap_map as plot_gap_map
