from ._metrics import fit_metrics as fit_metrics
from ._modes import eigenvalues as eigenvalues, modes as modes
