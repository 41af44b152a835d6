"""The package layout shows the pipeline: imports only run downwards, modules stay small,
and nothing reaches into JAX's private API."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "fwid"

# data -> reconstruction -> decomposition -> models -> simulation -> estimate -> validate /
# sensitivity -> design -> identification -> diagnosis -> report -> cli. `synth` (the embedded
# simulator) stands beside `data`, on its own; `_errors`, `_jax_setup` and the message
# helpers `_words` and `_advice` are the ground floor.
STAGES = ["_errors", "_jax_setup", "_words", "_advice", "data", "reconstruction",
          "decomposition", "models", "simulation", "estimate", "validate", "sensitivity", "design", "identification",
          "diagnosis", "report", "cli"]
RANK = {s: i for i, s in enumerate(STAGES)}
RANK["synth"] = RANK["data"]
RANK["_jax_setup"] = RANK["_errors"] = RANK["_words"] = RANK["_advice"] = 0
MAX_LINES = 500


def _modules():
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def _stage(parts: tuple[str, ...]) -> str:
    """The stage of a module given by its path parts below `fwid/`."""
    return parts[0].removesuffix(".py")


def _imports(path: Path, package: Path = PACKAGE):
    """(line, stage) of every fwid module `path` imports, at the top or inside a function."""
    rel = path.relative_to(package).parts
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:  # relative: climb from the module's package
                base = list(rel[:-1])[: len(rel) - node.level]
                target = base + (node.module.split(".") if node.module else [])
                if not target:  # `from .. import x` at the top of the package: x is a stage
                    for alias in node.names:
                        yield node.lineno, alias.name
                    continue
                yield node.lineno, target[0].removesuffix(".py")
            elif node.module and node.module.split(".")[0] == "fwid":
                parts = node.module.split(".")[1:]
                if parts:
                    yield node.lineno, parts[0]
                else:
                    for alias in node.names:
                        yield node.lineno, alias.name
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "fwid":
                    yield node.lineno, parts[1] if len(parts) > 1 else "fwid"


def test_every_module_has_a_stage():
    unknown = {_stage(p.relative_to(PACKAGE).parts) for p in _modules()} - set(RANK) - {"__init__"}
    assert not unknown, f"modules outside the pipeline's stages: {unknown}; add them to STAGES"


def test_imports_only_run_downwards():
    """No stage imports a later one (the flat API in `fwid/__init__.py` gathers them all)."""
    upward = []
    for path in _modules():
        rel = path.relative_to(PACKAGE).parts
        if rel == ("__init__.py",):
            continue
        own = _stage(rel)
        for line, target in _imports(path):
            if target == "fwid":  # `import fwid`: the public API, i.e. everything
                target = "cli" if own == "cli" else "fwid"
            if target not in RANK:  # a name from fwid's flat API
                if own != "cli":
                    upward.append(f"{'/'.join(rel)}:{line} imports fwid.{target} (the flat API)")
                continue
            if target != own and RANK[target] >= RANK[own]:
                upward.append(f"{'/'.join(rel)}:{line} ({own}) imports {target}")
    assert not upward, "imports against the pipeline's direction:\n" + "\n".join(upward)


def test_the_check_sees_an_upward_import(tmp_path):
    """The walker above finds relative and absolute upward imports, also inside functions."""
    pkg = tmp_path / "fwid"
    (pkg / "validate").mkdir(parents=True)
    src = ("from ..identification import x\n"
           "def f():\n    from fwid.report import y\n    from . import _metrics\n")
    (pkg / "validate" / "_bad.py").write_text(src)
    found = list(_imports(pkg / "validate" / "_bad.py", pkg))
    assert [t for _, t in found] == ["identification", "report", "validate"]



def _module_name(path: Path, package: Path) -> str:
    parts = list(path.relative_to(package.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Every module of `package` -> the modules of `package` it imports, at the top or inside a
    function. Importing `a.b.c` also runs the package `a.b` (unless the importer lives in it),
    so that package is an edge too."""
    paths = {_module_name(p, package): p for p in sorted(package.rglob("*.py"))
             if "__pycache__" not in p.parts}
    graph = {}
    for name, path in paths.items():
        own = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = own.split(".")[: len(own.split(".")) - node.level + 1]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                targets.add(mod)
                targets.update(f"{mod}.{a.name}" for a in node.names)  # `from . import _x`
            elif isinstance(node, ast.Import):
                targets.update(a.name for a in node.names)
        edges = set()
        for t in targets:
            if t not in paths:
                continue
            parts = t.split(".")
            for k in range(1, len(parts) + 1):  # the module and the packages it runs
                anc = ".".join(parts[:k])
                if anc in paths and anc != name and not own.startswith(anc):
                    edges.add(anc)
        graph[name] = edges
    return graph


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles of `graph`: its strongly connected components with more than one
    module (Tarjan's algorithm)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circle():
    """No module of fwid imports, directly or through others, a module that imports it."""
    circles = _circles(_import_graph())
    assert not circles, "import circles:\n" + "\n".join(" <-> ".join(c) for c in circles)


def test_the_check_sees_an_import_circle(tmp_path):
    """A circle through a function-level import and a package `__init__` is found; a package
    importing its own modules is not a circle."""
    pkg = tmp_path / "fwid"
    (pkg / "estimate").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "estimate" / "__init__.py").write_text("from ._fit import fit\n")
    (pkg / "estimate" / "_fit.py").write_text("from ._oe import fit_oe\ndef fit(): pass\n")
    (pkg / "estimate" / "_oe.py").write_text("from . import _problem\ndef fit_oe(): pass\n")
    (pkg / "estimate" / "_problem.py").write_text("X = 1\n")
    assert _circles(_import_graph(pkg)) == []
    (pkg / "estimate" / "_problem.py").write_text("def f():\n    from ._fit import fit\n")
    assert _circles(_import_graph(pkg)) == [["fwid.estimate._fit", "fwid.estimate._oe",
                                             "fwid.estimate._problem"]]


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_module_size(path):
    n = len(path.read_text().splitlines())
    assert n <= MAX_LINES, f"{path.relative_to(PACKAGE)} has {n} lines (at most {MAX_LINES}): split it by concept"


def test_no_private_jax_api():
    offenders = [str(p.relative_to(PACKAGE)) for p in _modules() if "jax._src" in p.read_text()]
    assert not offenders, f"modules reaching into JAX's private API: {offenders}"


def test_no_subpackage_is_named_like_a_public_name():
    """A subpackage and a function of one name leave a reader guessing which `fwid.x` is
    meant (and `import fwid.x._y` would replace the function by the module)."""
    import fwid

    subpackages = {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    clash = subpackages & set(fwid.__all__)
    assert not clash, f"subpackages named like public names of fwid: {sorted(clash)}"
