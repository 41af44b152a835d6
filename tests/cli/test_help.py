"""Help that reads right: a default said once and only where it tells something."""

import re

import pytest

from fwid.cli import COMMANDS, main


def _help(capsys, *args) -> str:
    with pytest.raises(SystemExit) as e:
        main([*args, "--help"])
    assert e.value.code == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_no_empty_or_doubled_default(command, capsys):
    text = _help(capsys, *([command] if command else []))
    flat = " ".join(text.split())
    for bad in ("(default: None)", "(default: True)", "(default: False)"):
        assert bad not in flat, (command, bad)
    options = re.split(r"\s(?=--?[a-z])", flat)  # one chunk per option
    assert all(chunk.count("(default") <= 1 for chunk in options), command
    assert "CONTRACTS" not in text


def test_design_is_summarised_by_its_default_criterion(capsys):
    flat = " ".join(_help(capsys).split())
    assert "(smallest parameter variances, or D-optimal)" in flat
    design = " ".join(_help(capsys, "design").split())
    assert "--criterion {variances,d-optimal}" in design


def test_identify_offers_the_methods_the_noise_models_and_fix(capsys):
    flat = " ".join(_help(capsys, "identify").split())
    assert "--method {output-error,equation-error,multiple-shooting,filter-error}" in flat
    assert "--noise {auto,full,diagonal}" in flat and "--fix NAME=VALUE" in flat
    assert "(default: output-" in flat  # argparse may wrap at the hyphen
