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


#: What a user's page must not hold: the internal interface notes, an issue number, a commit
#: hash, or a private module's file name (`_fit.py`, `fwid/estimate/_shooting.py`). History
#: belongs to CHANGELOG.md, how fwid decides inside to the contributors' pages.
INTERNAL = re.compile(r"CONTRACTS|\b[Ii]ssues? #?\d+"
                      r"|\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b"
                      r"|\b(?:commit|code of) [0-9a-f]{7,40}\b"
                      r"|(?:^|[^\w.])_[a-z][a-z0-9_]*\.py\b", re.M)


def _internal_mentions(text: str) -> list[str]:
    return [m.group(0).strip() for m in INTERNAL.finditer(text)]


def test_user_pages_hold_no_internal_notes():
    """README.md and the documentation pages (not the contributors' pages) name no internal
    notes, issue numbers, commit hashes or private module files."""
    docs = ROOT / "docs"
    pages = [ROOT / "README.md", *(p for p in docs.rglob("*.md")
                                   if "contributing" not in p.relative_to(docs).parts)]
    found = [f"{p.relative_to(ROOT)}:{n}: {hit}" for p in pages
             for n, line in enumerate(p.read_text().splitlines(), 1)
             for hit in _internal_mentions(line)]
    assert not found, "\n".join(found)


def test_internal_notes_check_can_fail():
    assert _internal_mentions("see CONTRACTS section 3, issue 13, 46d35b2 and the code of "
                              "2088021 (`fwid/estimate/_shooting.py`, `_riccati.py`)") == [
        "CONTRACTS", "issue 13", "46d35b2", "code of 2088021", "/_shooting.py", "`_riccati.py"]
    assert _internal_mentions("`tests/estimate/test_attas.py`, `benchmarks/diagnosis_power.py`, "
                              "`__init__.py`, 0.0253, 1e-10, a 3211 input") == []


def test_every_api_page_has_an_introduction():
    """Every stage's page (and `fwid.synth`'s) opens with its package docstring's paragraphs,
    which end with a sentence and name no private module file."""
    for stage in (*fwid.EXPORTS, "synth"):
        intro = _api.introduction(stage)
        assert intro, f"fwid/{stage}/__init__.py: no docstring to introduce its API page"
        assert intro.rstrip().endswith((".", ")", ":")) and not intro.rstrip().endswith(":"), \
            f"fwid.{stage}: its introduction stops mid-sentence: {intro[-60:]!r}"
        assert not _internal_mentions(intro), (stage, _internal_mentions(intro))
