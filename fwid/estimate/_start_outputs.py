"""Start values for models with an output equation `h`: what the least-squares start can do.

[`least_squares_start`][] regresses the differentiated measured states on `f` (equation
error); with an output equation `h` the outputs are not the states and that regression is
not available, so the free parameters it would set stay at the model's nominal values.
[`nominal_start`][] says so with a [`fwid.FitWarning`][] rather than silently (issue 13).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

from .._errors import FitWarning
from ..models._greybox import GreyBoxModel


def nominal_start(model: GreyBoxModel, kept: Sequence[str]) -> None:
    """Warn that `kept` (free parameters of a model with an output equation and states)
    start at their nominal values."""
    if not kept or model.outputs_are_states or not model.states:
        return
    names = ", ".join(kept[:6]) + (f" and {len(kept) - 6} more" if len(kept) > 6 else "")
    warnings.warn(
        f"{model.name}: the least-squares start keeps the nominal values of {names}: the "
        "model has an output equation h, so its outputs are not the measured states the "
        "equation-error start regresses; give start values (the model's params, or "
        "`start=model.with_params(...)`) close to the answer",
        FitWarning, stacklevel=4)
