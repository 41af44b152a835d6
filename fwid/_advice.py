"""What a fit's warnings and errors tell their user to do next: one step per failure, in the
user's own terms.

[`NEXT`][] is the decision: for each failure and the estimation method in use, the one step
to take. A method step never names the method in use, and the methods escalate one way only
(output error -> multiple shooting -> filter error -> equation error, the last needing no
simulation), so following the advice never loops; equation error's failures point to the
data (a window, a fixed parameter, more flights) or to `fwid diagnose`.

[`STEPS`][] holds each step's words: for a Python user the argument
(`method='multiple-shooting'`), for a command-line user the option (`--method
multiple-shooting`), and the option or command that takes it. The command line sets
[`command_line`][] around its work; every message that advises takes its words from
[`advise`][] (a failure's step) or [`advice`][] (a step named directly).
"""

from __future__ import annotations

import contextlib
import contextvars
from typing import NamedTuple


class Step(NamedTuple):
    """One next step: its words for a Python user and for a command-line user (`{name}`
    stands for a parameter's name), and the `fwid identify` option (`--fix`) or the `fwid`
    command (`diagnose`) that takes it (`DATA` for more flights on the command line)."""

    python: str
    cli: str
    flag: str


#: The estimation methods, in the order the advice escalates through them.
METHOD_ORDER = ("output-error", "multiple-shooting", "filter-error", "equation-error")


def _method(name: str) -> Step:
    return Step(f"fwid.fit(..., method='{name}')", f"--method {name}", "--method")


#: Every step a message can name.
STEPS = {
    **{m: _method(m) for m in METHOD_ORDER},
    "noise-diagonal": Step("noise='diagonal'", "--noise diagonal", "--noise"),
    "noise-full": Step("noise='full'", "--noise full", "--noise"),
    "fix": Step("fix {name} at a value you trust "
                "(model.with_params({{'{name}': VALUE}}).with_free(...) without it)",
                "--fix {name}=VALUE (a value you trust)", "--fix"),
    "window": Step("fit a stretch of steady, well-excited flight only (cut the flights)",
                   "--window START:END (a stretch of steady, well-excited flight)",
                   "--window"),
    "more-flights": Step("add flights whose designed inputs excite the parameters",
                         "add flights whose designed inputs excite the parameters (more DATA)",
                         "DATA"),
    "diagnose": Step("look for the missing effect (fwid.diagnose)",
                     "look for the missing effect (fwid diagnose --train DATA --test DATA)",
                     "diagnose"),
}

#: The decision: `NEXT[failure]` holds the step for each method of [`METHOD_ORDER`][].
NEXT = {
    # failure            output-error         multiple-shooting   filter-error      equation-error
    "diverged":         ("multiple-shooting", "filter-error",     "equation-error", "window"),
    "unstable":         ("multiple-shooting", "filter-error",     "equation-error", "window"),
    "not-converged":    ("multiple-shooting", "filter-error",     "equation-error", "fix"),
    "closed-loop":      ("filter-error",      "filter-error",     "equation-error", "more-flights"),
    "model-error":      ("filter-error",      "filter-error",     "diagnose",       "diagnose"),
    "ill-conditioned":  ("noise-diagonal",    "noise-diagonal",   "noise-diagonal", "noise-diagonal"),
    "singular":         ("fix",               "fix",              "fix",            "fix"),
    "no-information":   ("fix",               "fix",              "fix",            "more-flights"),
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


def next_step(failure: str, method: str | None = None) -> str:
    """The step ([`STEPS`][] key) after `failure` (a key of [`NEXT`][]) of a fit by `method`
    (default output error)."""
    method = method or "output-error"
    if method not in METHOD_ORDER:
        raise ValueError(f"method must be one of {', '.join(METHOD_ORDER)}, not {method!r}")
    return NEXT[failure][METHOD_ORDER.index(method)]


def advice(step: str, name: str = "NAME") -> str:
    """The words for `step` (a key of [`STEPS`][]) for the current user; `name`: the
    parameter a `fix` step names."""
    return getattr(STEPS[step], "cli" if _CLI.get() else "python").format(name=name)


def advise(failure: str, method: str | None = None, name: str = "NAME") -> str:
    """The words of the one next step after `failure` of a fit by `method` ([`next_step`][],
    [`advice`][])."""
    return advice(next_step(failure, method), name)
