"""Every file in `benchmarks/results/` starts with the command, the commit and the date that
produced it (`benchmarks/_provenance.py`, which every benchmark writer goes through)."""

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
sys.path.insert(0, str(ROOT / "benchmarks"))
import _provenance  # noqa: E402

KEYS = {"command", "commit", "date"}


def _check(path: Path) -> str | None:
    """Why `path` lacks its provenance, or None."""
    if path.suffix == ".md":
        head = path.read_text().splitlines()[:5]
        ok = any(l.startswith("Command: `python benchmarks/") and "commit `" in l
                 and "date " in l for l in head)
        return None if ok else "no 'Command: ... | commit ... | date ...' line under the title"
    if path.suffix == ".json":
        data = json.loads(path.read_text())
        ok = isinstance(data, dict) and KEYS <= set(data.get("provenance", {}))
        return None if ok else "no top-level 'provenance' with command, commit and date"
    if path.suffix == ".jsonl":
        first = json.loads(path.read_text().split("\n", 1)[0])
        return None if KEYS <= set(first.get("provenance", {})) else "first line not provenance"
    if path.suffix == ".png":
        from PIL import Image

        text = Image.open(path).info.get("Description", "")
        return None if text.startswith("Command: `python benchmarks/") else "no Description"
    return "a kind of file the provenance rules do not cover"


@pytest.mark.parametrize("path", sorted(RESULTS.iterdir()), ids=lambda p: p.name)
def test_results_file_carries_its_provenance(path):
    assert _check(path) is None, f"{path.name}: {_check(path)}"


def test_check_can_fail(tmp_path):
    bare = tmp_path / "x.md"
    bare.write_text("# x\n\nno provenance\n")
    assert _check(bare) is not None
    stamped = tmp_path / "y.md"
    prov = _provenance.provenance(["benchmarks/joint.py", "--seeds", "3"])
    stamped.write_text(_provenance.markdown("# y\n\nbody\n", prov))
    assert _check(stamped) is None
    assert prov["command"] == "python benchmarks/joint.py --seeds 3"


def test_writers_helpers(tmp_path):
    prov = {"command": "python benchmarks/a.py", "commit": "abc", "date": "d"}
    assert _provenance.stamped([1, 2], prov) == {"provenance": prov, "results": [1, 2]}
    assert list(_provenance.stamped({"a": 1}, prov)) == ["provenance", "a"]
    lines = tmp_path / "r.jsonl"
    lines.write_text(_provenance.jsonl_first_line(prov) + '{"kind": "single"}\n')
    assert _provenance.records(lines) == [{"kind": "single"}]
    assert _provenance.markdown("no title", prov).startswith("Command: `python benchmarks/a.py`")


def test_the_commit_says_when_fwid_is_not_this_checkouts(monkeypatch, tmp_path):
    """A results file records this checkout's commit: when the `fwid` imported is another
    copy's (an installed one, another worktree), the commit says so."""
    import sys
    import types

    fake = types.ModuleType("fwid")
    fake.__file__ = str(tmp_path / "elsewhere" / "fwid" / "__init__.py")
    monkeypatch.setitem(sys.modules, "fwid", fake)
    prov = _provenance.provenance(["benchmarks/joint.py"])
    assert f"(but fwid imported from {tmp_path / 'elsewhere' / 'fwid'})" in prov["commit"]
    fake.__file__ = str(_provenance.ROOT / "fwid" / "__init__.py")
    monkeypatch.setitem(sys.modules, "fwid", fake)
    assert "imported from" not in _provenance.provenance(["benchmarks/joint.py"])["commit"]
    # a script that runs fwid only as processes from this checkout (never imports it)
    monkeypatch.delitem(sys.modules, "fwid")
    assert "imported from" not in _provenance.provenance(["benchmarks/joint.py"])["commit"]
