"""Every documented command and snippet runs as written.

- The getting-started page's ```bash blocks run in order in a fresh folder, with fwid on the
  PATH, as a user copying them would: every command exits 0.
- Each guide page's ```python blocks run in order in one namespace, in a folder where the
  getting-started page's first command has written `demo/flights` (as the README's do in
  `tests/test_readme.py`).

A block preceded by `<!-- not run: REASON -->` (a command block that installs or takes long)
or `<!-- fragment: REASON -->` (a Python block that continues another page's, illustrative
only) is skipped; the reason is for the reader of the page's source.
"""

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parents[1] / "docs"
GETTING_STARTED = DOCS / "getting-started.md"
GUIDE = sorted((DOCS / "guide").glob("*.md"))

_BLOCK = re.compile(r"(?:^<!--\s*(?P<mark>[\w -]+?)\s*:(?P<why>.*?)-->\n)?^```(?P<lang>\w+)\n"
                    r"(?P<code>.*?)^```$", flags=re.S | re.M)
_SKIP = {"not run", "fragment"}


def blocks(text: str, lang: str, name: str = "page") -> tuple[list[str], list[str]]:
    """The `lang` blocks of a page's `text` to run, and the reasons of those marked as not to
    run."""
    run, skipped = [], []
    for m in _BLOCK.finditer(text):
        if m["lang"] != lang:
            continue
        if m["mark"]:
            assert m["mark"] in _SKIP, f"{name}: unknown marker <!-- {m['mark']}: -->"
            assert m["why"].strip(), f"{name}: <!-- {m['mark']}: --> without a reason"
            skipped.append(m["why"].strip())
        else:
            run.append(m["code"])
    return run, skipped


def _commands(block: str) -> list[str]:
    """The block's commands, one a line (a trailing backslash continues it; trailing
    `# comments` are bash's own)."""
    lines = block.replace("\\\n", " ").splitlines()
    return [line for line in lines if line.strip() and not line.lstrip().startswith("#")]


def test_markers_are_read():
    page = "x\n<!-- not run: slow -->\n```bash\nsleep 9\n```\n\n```bash\ntrue\n```\n" \
           "<!-- fragment: continues -->\n```python\nx\n```\n```python\ny = 1\n```\n"
    assert blocks(page, "bash") == (["true\n"], ["slow"])
    assert blocks(page, "python") == (["y = 1\n"], ["continues"])
    with pytest.raises(AssertionError, match="unknown marker"):
        blocks("<!-- skip: x -->\n```bash\ntrue\n```\n", "bash")


def test_getting_started_commands_run(tmp_path):
    fwid = Path(sys.executable).with_name("fwid")
    assert fwid.exists(), f"fwid is not installed beside {sys.executable}"
    env = {**os.environ, "PATH": f"{fwid.parent}{os.pathsep}{os.environ.get('PATH', '')}",
           "MPLBACKEND": "Agg"}
    run, skipped = blocks(GETTING_STARTED.read_text(), "bash", GETTING_STARTED.name)
    assert len(run) >= 2 and len(skipped) <= 1, (len(run), skipped)
    assert shutil.which("fwid", path=env["PATH"]) == str(fwid)
    for i, block in enumerate(run):
        for command in _commands(block):
            done = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=env,
                                  capture_output=True, text=True, timeout=300)
            assert done.returncode == 0, (
                f"getting-started.md bash block {i + 1}: `{command}` exits {done.returncode}\n"
                f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
    # what the page says the commands write
    for path in ("demo/report/report.json", "flights/train/vehicle.json",
                 "diagnosis/diagnosis.json", "next/input.csv"):
        assert (tmp_path / path).exists(), path
    # the effect the page says the diagnosis finds
    assert json.loads((tmp_path / "diagnosis/diagnosis.json").read_text())["verdict"] == \
        "nonlinear-aero"
    # and the page's Python, in the folder the commands wrote
    code, _ = blocks(GETTING_STARTED.read_text(), "python", GETTING_STARTED.name)
    _exec_page(GETTING_STARTED, code, tmp_path)


def _exec_page(path: Path, code: list[str], folder: Path) -> dict:
    cwd = os.getcwd()
    os.chdir(folder)
    namespace: dict = {}
    try:
        for i, block in enumerate(code):
            try:
                exec(compile(block, f"{path.name} python block {i + 1}", "exec"), namespace)
            except Exception as e:  # name the block, for the page's author
                raise AssertionError(
                    f"{path.name} python block {i + 1} fails: {e!r}\n{block}") from e
    finally:
        os.chdir(cwd)
        import matplotlib.pyplot as plt

        plt.close("all")
    return namespace


_GUIDE_PYTHON = [p for p in GUIDE if "```python" in p.read_text()]


@pytest.mark.parametrize("page", _GUIDE_PYTHON, ids=[p.stem for p in _GUIDE_PYTHON])
def test_guide_python_runs(page, tmp_path):
    from fwid.synth import write_flights

    code, _ = blocks(page.read_text(), "python", page.name)
    if not code:
        pytest.skip(f"{page.name}: every Python block is marked as a fragment")
    write_flights(tmp_path / "demo" / "flights", n_flights=2, seed=0)
    _exec_page(page, code, tmp_path)
