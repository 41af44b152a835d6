"""Write the API reference pages, `docs/api/*.md`, from `fwid.EXPORTS`.

One page per stage (subpackage), in the order of `fwid.EXPORTS`, each public name rendered by
mkdocstrings from its docstring, plus a page for the errors and warnings and an index.
`tests/test_docs.py` fails when the committed pages differ from what this script writes:
after adding a public name to `fwid.EXPORTS`, run `python docs/_api.py`.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
API = ROOT / "docs" / "api"

#: The errors and warnings that `fwid/__init__.py` imports itself (not in `EXPORTS`).
ERRORS = ("FwidError", "InputError", "FlightDataError", "ExcitationError", "FitDivergedError",
          "FitWarning", "DiagnosisWarning")


def _summary(stage: str) -> str:
    """The first line of a stage package's docstring (read without importing it)."""
    init = ROOT / "fwid" / stage / "__init__.py"
    doc = ast.get_docstring(ast.parse(init.read_text())) if init.exists() else None
    return doc.strip().splitlines()[0] if doc else ""


def locate(name: str) -> str:
    """The path of the module that defines the public name `name` of fwid, dotted with the name
    (`fwid.data._flight.Flight`): mkdocstrings reads it there, without importing fwid."""
    import importlib

    import fwid

    obj = getattr(fwid, name)
    module = getattr(obj, "__module__", None)
    if module and module.startswith("fwid") and getattr(
            importlib.import_module(module), name, None) is obj:
        return f"{module}.{name}"
    # a constant: the module of its stage that assigns it
    package = importlib.import_module(f"fwid.{fwid._STAGE[name]}")
    for path in sorted(Path(package.__file__).parent.glob("*.py")):
        for node in ast.parse(path.read_text()).body:
            targets = getattr(node, "targets", None) or [getattr(node, "target", None)]
            if any(getattr(t, "id", None) == name for t in targets):
                return f"{package.__name__}.{path.stem}.{name}"
    raise LookupError(f"fwid.{name}: no module of its stage defines it")


def pages(exports: dict[str, tuple[str, ...]], where=locate) -> dict[str, str]:
    """The text of every API page, by file name, for the stages and names of `exports`;
    `where(name)` gives the dotted path that defines a name."""
    out = {}
    index = ["# API reference", "",
             "Every public name is available flat, as `fwid.NAME` (`import fwid` stays light: a "
             "name's stage is imported on first use). The pages below group them by the stage "
             "that defines them, in the order the stages run; imports only run down this list.",
             "", "| stage | names |", "|---|---|"]
    for stage, names in exports.items():
        lines = [f"# `fwid.{stage}`", ""]
        summary = _summary(stage)
        if summary:
            lines += [summary, ""]
        for name in names:
            # the stage's own path too, which docstrings use (`fwid.decomposition.lowpass`)
            lines += [f"[](){{#fwid.{name}}}", f"[](){{#fwid.{stage}.{name}}}",
                      f"::: {where(name)}", ""]
        out[f"{stage}.md"] = "\n".join(lines)
        links = ", ".join(f"[`{n}`]({stage}.md#fwid.{n})" for n in names)
        index.append(f"| [`fwid.{stage}`]({stage}.md) | {links} |")
    lines = ["# Errors and warnings", "",
             "Bad input raises `fwid.InputError` or `fwid.FlightDataError` with one line that "
             "names what, where and how to fix it; the command line turns them into exit code 2 "
             "without a traceback. `fwid.__version__` is the installed version.", ""]
    for name in ERRORS:
        lines += [f"[](){{#fwid.{name}}}", f"::: fwid._errors.{name}", ""]
    out["errors.md"] = "\n".join(lines)
    index.append("| [errors and warnings](errors.md) | "
                 + ", ".join(f"[`{n}`](errors.md#fwid.{n})" for n in ERRORS) + " |")
    out["index.md"] = "\n".join(index) + "\n"
    return out


def main() -> None:
    sys.path.insert(0, str(ROOT))
    import fwid

    API.mkdir(parents=True, exist_ok=True)
    for old in API.glob("*.md"):
        old.unlink()
    for name, text in pages(fwid.EXPORTS).items():
        (API / name).write_text(text)


if __name__ == "__main__":
    main()
