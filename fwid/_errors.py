"""Error types raised by fwid.

Every error that comes from the user's input (files, columns, units, excitation) is a
[`fwid.InputError`][]; the command line turns those into a one-line message and exit code 2.
"""


class FwidError(Exception):
    """Base class of every error fwid raises on purpose."""


class InputError(FwidError, ValueError):
    """Bad input: the message names what is wrong, where, and how to fix it."""


class FlightDataError(InputError):
    """A flight file (or its sidecar / `vehicle.json`) that cannot be used as it is."""


class ExcitationError(InputError):
    """The data do not excite the model enough to identify its free parameters;
    `parameters` names them where the estimator found them (`bq@1`: flight 1's copy of a
    per-flight term), else it is empty."""

    def __init__(self, *args, parameters=()):
        super().__init__(*args)
        self.parameters = tuple(parameters)


class FitDivergedError(FwidError, RuntimeError):
    """The estimator failed to converge (the simulation blew up or the cost did not decrease)."""


class FitWarning(UserWarning):
    """A fit that finished but should not be trusted as it is: not converged, R
    ill-conditioned, parameters nearly unidentifiable, or not finite. Filter it with
    `warnings.filterwarnings("ignore", category=fwid.FitWarning)`."""


class DiagnosisWarning(UserWarning):
    """A diagnosis that ran but may answer a different question than meant (e.g. the axis
    diagnosed is not the one the flights manoeuvre in)."""
