"""The documentation site builds offline with `mkdocs build --strict`, and its API reference
lists every public name of `fwid.__all__` (pages written by `docs/_api.py` from `fwid.EXPORTS`)."""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import fwid

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs"))
import _api  # noqa: E402  (docs/_api.py: the API pages' writer)

_NO_MKDOCS = importlib.util.find_spec("mkdocs") is None
_REASON = "mkdocs is not installed (pip install -e '.[docs]' or '.[dev]')"


def _public() -> list[str]:
    return [n for n in fwid.__all__ if n != "__version__"]


def test_api_pages_match_exports():
    """The committed API pages are what `python docs/_api.py` writes from `fwid.EXPORTS`."""
    expected = _api.pages(fwid.EXPORTS)
    committed = {p.name: p.read_text() for p in (ROOT / "docs" / "api").glob("*.md")}
    assert sorted(committed) == sorted(expected), "run `python docs/_api.py`"
    for name, text in expected.items():
        assert committed[name] == text, f"docs/api/{name} is stale: run `python docs/_api.py`"
    listed = set(re.findall(r"\{#fwid\.(\w+)\}", "".join(committed.values())))
    assert set(_public()) <= listed


def test_api_pages_fail_on_a_missing_name():
    """The check above can fail: a name added to EXPORTS changes the pages."""
    exports = {**fwid.EXPORTS, "data": (*fwid.EXPORTS["data"], "load_vehicle")}
    assert _api.pages(exports, where=lambda n: f"x.{n}") != _api.pages(
        fwid.EXPORTS, where=lambda n: f"x.{n}")


@pytest.mark.skipif(_NO_MKDOCS, reason=_REASON)
def test_site_builds_strict_offline(tmp_path):
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q",
                           "-f", str(ROOT / "mkdocs.yml"), "-d", str(site)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    html = "".join(p.read_text() for p in (site / "api").rglob("*.html"))
    missing = [n for n in _public() if f'id="fwid.{n}"' not in html]
    assert not missing, f"not in the API reference: {missing}"
    # every guide page and notebook rendered; nothing that reads from the network
    for page in ("getting-started", "guide/data", "guide/diagnosis", "notebooks/04_diagnosis",
                 "benchmarks/index", "changelog"):
        assert (site / f"{page}.html").exists(), page
    remote = [p.name for p in site.rglob("*.html") if re.search(
        r'<(?:script|link)[^>]+(?:src|href)="https?://', p.read_text())]
    assert not remote, f"pages that load something from the network: {remote}"
    assert not (ROOT / ".cache").exists() or not any((ROOT / ".cache").glob("mkdocs-jupyter*"))


#: The stages whose public docstrings are in the anchors' form (diffrax's): a one-line
#: summary, then `**Arguments:**` and `**Returns:**` (a class: its `**Fields:**` or
#: `**Arguments:**`).
ANCHOR_FORM = ("data", "reconstruction", "decomposition", "models", "simulation", "validate", "sensitivity",
               "report", "identification")


def _form_problems(name, obj) -> list[str]:
    import inspect

    doc = inspect.getdoc(obj) or ""
    problems = []
    if not doc or "\n" in doc.split("\n\n")[0]:
        problems.append(f"{name}: the summary is not one line")
    if inspect.isclass(obj):
        if not any(k in doc for k in ("**Arguments:**", "**Fields:**", "**Attributes:**")):
            problems.append(f"{name}: no **Fields:** or **Arguments:**")
    else:
        for key in ("**Arguments:**", "**Returns:**"):
            if key not in doc:
                problems.append(f"{name}: no {key}")
    return problems


def test_public_docstrings_in_the_anchors_form():
    problems = [p for stage in ANCHOR_FORM for n in fwid.EXPORTS.get(stage, ())
                for p in _form_problems(n, getattr(fwid, n))]
    assert not problems, "\n".join(problems)


def test_docstring_form_check_can_fail():
    def f(x):
        """Two lines
        of summary."""

    assert _form_problems("f", f) == ["f: the summary is not one line", "f: no **Arguments:**",
                                      "f: no **Returns:**"]


@pytest.mark.skipif(_NO_MKDOCS or importlib.util.find_spec("griffe") is None, reason=_REASON)
def test_lists_in_docstrings_get_their_blank_line():
    import _griffe  # docs/_griffe.py

    text = "Summary.\n\n**Arguments:**\n- `x`: one,\n  continued.\n- `y`: two.\n\n```\n- not a list\n```"
    assert _griffe.blank_line_before_lists(text) == text.replace(":**\n-", ":**\n\n-")
