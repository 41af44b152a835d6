"""Advice as a decision: every failure names one next step, never the method in use, the
steps never loop, and every step a message names is an option (or a command) of `fwid`."""

import argparse
import re
from types import SimpleNamespace

import numpy as np
import pytest

from fwid._advice import METHOD_ORDER, NEXT, STEPS, advise, command_line, next_step
from fwid.cli._parser import parser
from fwid.estimate._warnings import fit_warnings
from fwid.report import failure_reason


def _commands():
    sub = next(a for a in parser()._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


def _identify_options():
    ident = _commands()["identify"]
    return {o for a in ident._actions for o in a.option_strings}, ident


def _options_of(command):
    return {o for a in _commands()[command]._actions for o in a.option_strings}


def test_the_advice_graph_has_no_cycle_and_never_the_method_in_use():
    for failure, row in NEXT.items():
        assert len(row) == len(METHOD_ORDER), failure
        for method in METHOD_ORDER:
            seen, at = [method], method
            while at in METHOD_ORDER:  # follow the advice while it names a method
                at = next_step(failure, at)
                assert at in STEPS, (failure, at)
                assert at != seen[-1], f"{failure}: {seen[-1]} -> itself"
                assert at not in seen, f"{failure}: a loop {' -> '.join(seen + [at])}"
                seen.append(at)
    # equation error needs no simulation: its failures point to the data or the model
    assert {next_step(f, "equation-error") for f in NEXT} <= {
        "window", "fix", "more-flights", "noise-diagonal", "diagnose"}
    with pytest.raises(ValueError, match="method must be one of"):
        next_step("diverged", "least-squares")


def test_every_step_has_its_option_or_command():
    options, ident = _identify_options()
    methods = next(a for a in ident._actions if "--method" in a.option_strings).choices
    assert set(METHOD_ORDER) <= set(methods)
    for key, step in STEPS.items():
        if step.flag.startswith("--"):
            assert step.flag in options, key
        elif step.flag == "DATA":
            assert any(a.dest == "data" and a.nargs == "+" for a in ident._actions)
        else:
            assert step.flag in _commands(), key
        with command_line():
            assert step.flag in advice_words(key), key
    noise = next(a for a in ident._actions if "--noise" in a.option_strings).choices
    assert set(noise) == {"auto", "full", "diagonal"}


def advice_words(key):
    from fwid._advice import advice

    return advice(key, "Xw")


def _named_flags(text):
    """The options and commands a message's next step names."""
    step = text.rsplit("next: ", 1)[1]
    return re.findall(r"(?<![\w-])--[a-z][a-z-]*", step), re.findall(r"\bfwid ([a-z]+)", step)


def _failing_result(finite=True):
    """Every warning at once: not converged, R ill-conditioned, residuals of model error,
    a pair correlated beyond 0.98 (or, not `finite`, an estimate that is not)."""
    return SimpleNamespace(
        model=SimpleNamespace(name="lon", outputs=("q", "w")), names=("Mq", "Mw"),
        theta=np.array([1.0, 2.0 if finite else np.nan]), std=np.array([0.1, 0.2]),
        cost=1.0, converged=False, steps=1, active=None,
        R=np.array([[1.0, 1 - 1e-12], [1 - 1e-12, 1.0]]),
        corr=np.array([[1.0, 0.999], [0.999, 1.0]]),
        colour=np.array([0.9, 0.8]), residual_corr=np.array([[1.0, 0.9], [0.9, 1.0]]))


def _reports(method):
    base = {"model": "lon", "flights": ["f.csv"], "method": method, "closed_loop": {},
            "fit": {"cost": 1.0}, "eigenvalues": [[-1.0, 0.0]],
            "metrics": {"estimation": {"q": {"r2": 0.2}}}}
    return [base, {**base, "fit": {"cost": None}},
            {**base, "eigenvalues": [[0.8, 0.0]]},
            {**base, "metrics": {"estimation": {"q": {"r2": -1e9, "diverged_at_s": 3.0}}}}]


@pytest.mark.parametrize("method", METHOD_ORDER)
def test_each_methods_failure_messages_name_one_step_with_an_existing_flag(method):
    options, _ = _identify_options()
    with command_line():
        messages = [*fit_warnings(_failing_result(), ["f.csv"], 60, method=method),
                    *fit_warnings(_failing_result(False), ["f.csv"], 60, method=method),
                    *(failure_reason(r) for r in _reports(method))]
    assert len(messages) >= 8
    for text in messages:
        assert text.count("next: ") == 1, text
        flags, commands = _named_flags(text)
        assert flags or commands, text
        assert set(commands) <= set(_commands()), text
        # the options of the command the step names, else those of fwid identify
        assert set(flags) <= (_options_of(commands[0]) if commands else options), text
        assert f"--method {method}" not in text.rsplit("next: ", 1)[1], text
        assert "fwid.fit" not in text and "with_free" not in text, text  # the Python words


def test_python_users_get_the_argument_and_cli_users_the_option():
    assert advise("not-converged", "output-error") == "fwid.fit(..., method='multiple-shooting')"
    with command_line():
        assert advise("not-converged", "output-error") == "--method multiple-shooting"
        assert advise("singular", "filter-error", "Xw").startswith("--fix Xw=VALUE")
    assert "model.with_params({'Xw': VALUE})" in advise("singular", "filter-error", "Xw")
