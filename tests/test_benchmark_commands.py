"""Every case the README's and the guide's benchmark commands name resolves, down to the
module attributes its runner reads, without running a fit (a function that hides the module
of the same name fails here, not after minutes of benchmark)."""

import dis
import re
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import textbook_cases  # noqa: E402


def _documented_cases() -> set[str]:
    text = "".join(p.read_text() for p in [ROOT / "README.md", *ROOT.glob("docs/**/*.md")])
    found = re.findall(r"textbook_cases\.py[^`\n]*--cases ([\w,]+)", text)
    return {k for group in found for k in group.split(",")}


def _attribute_reads(code: types.CodeType):
    """`(global name, attribute)` for every `NAME.attr` the code reads."""
    ops = list(dis.get_instructions(code))
    for a, b in zip(ops, ops[1:]):
        if a.opname == "LOAD_GLOBAL" and b.opname in ("LOAD_ATTR", "LOAD_METHOD"):
            yield a.argval, b.argval
    for const in code.co_consts:  # nested functions and comprehensions
        if isinstance(const, types.CodeType):
            yield from _attribute_reads(const)


def test_the_documented_commands_name_cases():
    assert {"tc08", "tc04_fem"} <= _documented_cases()


@pytest.mark.parametrize("key", sorted(_documented_cases()))
def test_every_documented_case_resolves(key):
    known = {**textbook_cases.CASES, **textbook_cases.HARD, **textbook_cases.RUNNERS}
    assert key in known, f"{key}: not a case of benchmarks/textbook_cases.py"
    runner = known[key]
    for name, attr in _attribute_reads(runner.__code__):
        obj = runner.__globals__.get(name)
        if obj is None:
            continue  # a builtin
        assert hasattr(obj, attr), f"{key}: {name}.{attr} does not resolve ({type(obj)})"
