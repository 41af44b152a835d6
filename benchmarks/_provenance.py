"""Provenance of a results file: the command, the git commit and the date that produced it.

Every writer of `benchmarks/results/` goes through this module, so each file starts with them:
a Markdown file with a `Command: ... | commit ... | date ...` line under its title, a JSON file
with a top-level `"provenance"` key (a list of records becomes `{"provenance", "results"}`), a
JSON-lines file with a first line `{"provenance": ...}` (`records` skips it when reading), a
PNG figure with the same line as its `Description` text chunk.
"""

from __future__ import annotations

import datetime
import json
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# this checkout's fwid before any installed one, so that the commit recorded is the code run
# (a script imports this module before fwid)
if str(ROOT) not in sys.path:
    sys.path.insert(1, str(ROOT))


def provenance(argv: list[str] | None = None) -> dict:
    """The command line (`python benchmarks/NAME.py ARGS`), the commit of the checkout (with
    `+dirty` when it has uncommitted changes, and where `fwid` came from when it is not this
    checkout's) and the UTC date and time."""
    argv = sys.argv if argv is None else argv
    script = Path(argv[0]).resolve()
    try:
        script = script.relative_to(ROOT)
    except ValueError:
        pass
    command = " ".join(["python", shlex.quote(str(script)), *map(shlex.quote, argv[1:])])

    def git(*args):
        try:
            return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True,
                                  text=True, timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""

    commit = git("rev-parse", "--short=12", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += "+dirty"
    fwid = sys.modules.get("fwid")
    where = Path(getattr(fwid, "__file__", None) or ROOT / "fwid" / "__init__.py").resolve()
    if ROOT not in where.parents:  # the code run is not this checkout's: say whose it is
        commit += f" (but fwid imported from {where.parent})"
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return {"command": command, "commit": commit, "date": date}


def header(prov: dict) -> str:
    """The Markdown line that carries `prov`."""
    return f"Command: `{prov['command']}` | commit `{prov['commit']}` | date {prov['date']}"


def markdown(text: str, prov: dict | None = None) -> str:
    """`text` with the provenance line under its first `# ` title (at the top if none)."""
    line = header(prov or provenance())
    lines = text.split("\n")
    for i, row in enumerate(lines):
        if row.startswith("# "):
            return "\n".join([*lines[:i + 1], "", line, *lines[i + 1:]])
    return "\n".join([line, "", *lines])


def stamped(obj, prov: dict | None = None):
    """A JSON value with `"provenance"` first: a dict gains the key, a list is wrapped."""
    prov = prov or provenance()
    if isinstance(obj, dict):
        return {"provenance": prov, **{k: v for k, v in obj.items() if k != "provenance"}}
    return {"provenance": prov, "results": obj}


def json_text(obj, prov: dict | None = None, **dumps) -> str:
    """`json.dumps` of `stamped(obj)`, with a final newline."""
    return json.dumps(stamped(obj, prov), **dumps) + "\n"


def jsonl_first_line(prov: dict | None = None) -> str:
    """The first line of a JSON-lines results file."""
    return json.dumps({"provenance": prov or provenance()}) + "\n"


def records(path) -> list[dict]:
    """The records of a JSON-lines results file, without its provenance line."""
    rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
    return [r for r in rows if set(r) != {"provenance"}]
