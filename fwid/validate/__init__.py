from ._metrics import fit_metrics as fit_metrics
from ._modes import eigenvalues as eigenvalues, modes as modes
from ._sensitivity import (
    cutoff_cost as cutoff_cost,
    eigenvalue_sensitivity as eigenvalue_sensitivity,
    estimate_sensitivity_to_cutoff as estimate_sensitivity_to_cutoff,
    metric_sensitivity as metric_sensitivity,
    output_sensitivity as output_sensitivity,
    rank_sensitivities as rank_sensitivities,
)
