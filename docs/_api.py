"""Write the API reference pages, `docs/api/*.md`, from `fwid.EXPORTS`.

One page per stage (subpackage), in the order of `fwid.EXPORTS`, each public name rendered by
mkdocstrings from its docstring, plus a page for the embedded simulator `fwid.synth` (the names
of `SYNTH`), a page for the errors and warnings and an index. A page starts with its package
docstring's paragraphs up to the map of its modules (`introduction`); a constant is shown as a
table built from its value, with the `#:` comment above its assignment as its description.
`tests/test_docs.py` fails when the committed pages differ from what this script writes:
after adding a public name to `fwid.EXPORTS`, run `python docs/_api.py`.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
API = ROOT / "docs" / "api"

#: The errors and warnings that `fwid/__init__.py` imports itself (not in `EXPORTS`).
ERRORS = ("FwidError", "InputError", "FlightDataError", "ExcitationError", "FitDivergedError",
          "FitWarning", "DiagnosisWarning")


#: A private module's file name (`_fit.py`): a package docstring's introduction ends before the
#: first paragraph that names one (the map of the package's modules, for contributors).
PRIVATE_FILE = re.compile(r"(?<![\w./])_[a-z][a-z0-9_]*\.py\b")


def introduction(stage: str) -> str:
    """The introduction of a stage's page: its package docstring (read without importing it),
    whole paragraphs up to the first one that names a private module's file or that reads
    "The modules:" (the map of the package, which is for contributors); "" without one."""
    init = ROOT / "fwid" / stage / "__init__.py"
    doc = ast.get_docstring(ast.parse(init.read_text())) if init.exists() else None
    kept = []
    for para in (doc or "").strip().split("\n\n"):
        if PRIVATE_FILE.search(para) or para.strip() == "The modules:":
            break
        kept.append(para.strip())
    return "\n\n".join(kept)


def _comment_above(path: Path, lineno: int) -> str:
    """The `#:` comment lines right above line `lineno` of `path` (a constant's description)."""
    lines = path.read_text().splitlines()[:lineno - 1]
    out = []
    while lines and lines[-1].lstrip().startswith("#:"):
        out.insert(0, lines.pop().lstrip()[2:].strip())
    return " ".join(out)


def _assignment(package: str, name: str) -> tuple[str, str]:
    """The dotted module that assigns the constant `name` in `package` (searched recursively),
    and the description in the `#:` comment above it."""
    import importlib

    pkg = importlib.import_module(package)
    base = Path(pkg.__file__).parent
    for path in sorted(base.rglob("*.py")):
        for node in ast.parse(path.read_text()).body:
            targets = getattr(node, "targets", None) or [getattr(node, "target", None)]
            if any(getattr(t, "id", None) == name for t in targets):
                parts = path.relative_to(base).with_suffix("").parts
                parts = parts[:-1] if parts[-1] == "__init__" else parts
                return ".".join((package, *parts)), _comment_above(path, node.lineno)
    raise LookupError(f"{package}.{name}: no module of its package defines it")


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def constant_table(value) -> list[str]:
    """A constant rendered for people: a table of the catalogue's effects, of a mapping's
    entries, or the items of a tuple of names; [] for anything else (its docstring says it)."""
    if isinstance(value, tuple) and value and all(hasattr(v, "description") for v in value):
        rows = ["| effect | what it adds to the model | band | forms tried |", "|---|---|---|---|"]
        for e in value:
            n = len(getattr(e, "variants", (None,)))
            rows.append(f"| `{e.name}` | {_cell(e.description)} | {e.band} | {n} |")
        return rows
    if isinstance(value, dict) and all(isinstance(v, tuple) for v in value.values()):
        rows = ["| key | values |", "|---|---|"]
        rows += [f"| `{k}` | {', '.join(f'`{x}`' for x in v)} |" for k, v in value.items()]
        return rows
    if isinstance(value, tuple) and all(isinstance(v, str) for v in value):
        return [", ".join(f"`{v}`" for v in value)]
    fields = getattr(value, "__dataclass_fields__", None)
    if fields:
        rows = ["| field | value |", "|---|---|"]
        rows += [f"| `{k}` | {getattr(value, k):.6g} |" for k in fields
                 if isinstance(getattr(value, k), (int, float))]
        return rows
    return []


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
    return f"{_assignment(f'fwid.{fwid._STAGE[name]}', name)[0]}.{name}"


#: The names of `fwid.synth`, the embedded simulator (not in `fwid.EXPORTS`: no stage imports
#: it), that its page documents: the ones the notebooks and the guide use.
SYNTH = ("write_flights", "simulate_flight", "write_csv", "write_vehicle", "write_sidecar",
         "write_raw_flights", "simulate_raw", "DelFly", "DELFLY", "random_vehicle",
         "effect_noise_ratio", "EFFECTS", "OUT_OF_CATALOGUE", "FORMS", "form_axes", "make_input")


def _is_constant(obj) -> bool:
    import inspect

    return not (callable(obj) or inspect.ismodule(obj))


def _constant(qualified: str, package: str, name: str, value) -> list[str]:
    """A constant's section: its name as a heading, its `#:` description, and its value as a
    table (never the raw repr of its objects)."""
    _, description = _assignment(package, name)
    out = [f"## `{name}`", ""]
    if description:
        out += [description, ""]
    table = constant_table(value)
    out += [*table, ""] if table else [f"A `{type(value).__name__}`.", ""]
    return out


def _stage_page(title: str, intro: str, package: str, names, where, anchors) -> list[str]:
    import importlib

    mod = importlib.import_module(package)
    lines = [title, ""]
    if intro:
        lines += [intro, ""]
    for name in names:
        lines += [*(f"[](){{#{a}}}" for a in anchors(name))]
        value = getattr(mod, name)
        if _is_constant(value):
            lines += _constant(package, package, name, value)
        else:
            lines += [f"::: {where(name)}", ""]
    return lines


def _synth_where(name: str) -> str:
    import importlib

    import fwid.synth

    obj = getattr(fwid.synth, name)
    module = getattr(obj, "__module__", None)
    if module and module.startswith("fwid.synth") and getattr(
            importlib.import_module(module), name, None) is obj:
        return f"{module}.{name}"
    return f"{_assignment('fwid.synth', name)[0]}.{name}"


def pages(exports: dict[str, tuple[str, ...]], where=locate) -> dict[str, str]:
    """The text of every API page, by file name, for the stages and names of `exports`;
    `where(name)` gives the dotted path that defines a name. Each stage's page starts with
    its package's `introduction`; a constant is shown as a table (`constant_table`)."""
    out = {}
    index = ["# API reference", "",
             "Every public name is available flat, as `fwid.NAME` (`import fwid` stays light: a "
             "name's stage is imported on first use). The pages below group them by the stage "
             "that defines them, in the order the stages run; imports only run down this list.",
             "", "| stage | names |", "|---|---|"]
    for stage, names in exports.items():
        # the stage's own path too, which docstrings use (`fwid.decomposition.lowpass`)
        lines = _stage_page(f"# `fwid.{stage}`", introduction(stage), f"fwid.{stage}", names,
                            where, lambda n, st=stage: (f"fwid.{n}", f"fwid.{st}.{n}"))
        out[f"{stage}.md"] = "\n".join(lines)
        links = ", ".join(f"[`{n}`]({stage}.md#fwid.{n})" for n in names)
        index.append(f"| [`fwid.{stage}`]({stage}.md) | {links} |")
    lines = _stage_page("# `fwid.synth`", introduction("synth"),
                        "fwid.synth", SYNTH, _synth_where if where is locate else where,
                        lambda n: (f"fwid.synth.{n}",))
    out["synth.md"] = "\n".join(lines)
    index.append("| [`fwid.synth`](synth.md) (beside the stages: the default data) | "
                 + ", ".join(f"[`{n}`](synth.md#fwid.synth.{n})" for n in SYNTH) + " |")
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
