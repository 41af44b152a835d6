"""What a fit's warnings and errors tell their user to try, in the user's own terms.

A Python user is told the argument (`method='multiple-shooting'`); a command-line user the
option (`--method multiple-shooting`) or, where the command line has none, the Python call.
The command line sets [`command_line`][] around its work; every message that advises takes
its words from [`advice`][].
"""

from __future__ import annotations

import contextlib
import contextvars

#: Each remedy: its words for a Python user, and for a command-line user.
REMEDIES = {
    "multiple-shooting": ("fwid.fit(..., method='multiple-shooting')",
                          "--method multiple-shooting"),
    "filter-error": ("method='filter-error'", "--method filter-error"),
    "diagonal-noise": ("noise='diagonal'", "the Python call fwid.fit(..., noise='diagonal')"),
    "full-noise": ("noise='full'", "the Python call fwid.fit(..., noise='full')"),
    "max-steps": ("raise max_steps", "raise max_steps (the Python call fwid.fit(..., "
                  "max_steps=...))"),
    "fix": ("`model.with_free(...)`", "pin them with --prior and a tiny std, or in Python "
            "`model.with_free(...)`"),
    "start": ("give start values (`start=model.with_params(...)`)",
              "give start values (the Python call fwid.fit(..., "
              "start=model.with_params(...)))"),
}

#: Set (in this thread or task only) by `command_line`.
_CLI: contextvars.ContextVar[bool] = contextvars.ContextVar("fwid_advice_cli", default=False)


@contextlib.contextmanager
def command_line():
    """Inside, [`advice`][] speaks to a command-line user (this thread or task only)."""
    token = _CLI.set(True)
    try:
        yield
    finally:
        _CLI.reset(token)


def advice(remedy: str) -> str:
    """The words for `remedy` (a key of [`REMEDIES`][]) for the current user."""
    return REMEDIES[remedy][1 if _CLI.get() else 0]
