"""The batched estimator kept whole across processes: a `jax.export` artifact on disk.

JAX's persistent compilation cache (`fwid._jax_setup`) spares a new process the XLA
compilation, but every process still traces and lowers the program first: for the batched
output-error fit about 1.7 s of a warm 16-flight `fwid identify`
(`benchmarks/results/speed_process.md`). Here the traced and lowered program itself is kept,
serialised by `jax.export`, in the `exported/` folder of the compilation cache, so a later
process deserialises it (milliseconds) and only loads its compiled form.

A kept program must never stand in for a different one, so its file name is a digest of
everything that shapes it: fwid's own source files, the versions of JAX and the libraries
that build the program (equinox, diffrax, optimistix, lineax), float64 on or off, the
function, every static argument (the model's functions, names and options) and the shape
and dtype of every array argument, and the device mesh. A model whose functions are not
fwid's own (a user's `GreyBoxModel`, a lambda, a closure) cannot be described that way: it is
traced as before. The cache is off with the compilation cache (`FWID_JAX_CACHE=off`), and
across processes of a cluster (`_distributed.py`).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import importlib.metadata
import os
import types
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from .._jax_setup import cache_folder

#: Packages whose code may appear in a kept program, with their versions in the key.
LIBRARIES = ("jax", "jaxlib", "equinox", "diffrax", "optimistix", "lineax")
#: Modules whose functions and classes may be static parts of a kept program.
TRUSTED = ("fwid.", "diffrax", "optimistix", "lineax", "equinox", "jax.", "numpy")


class _Unkeyable(Exception):
    """A static argument that the digest cannot describe (a user's function)."""


@functools.cache
def _environment() -> str:
    """fwid's source files and the libraries' versions, digested once per process."""
    h = hashlib.sha256()
    root = Path(__file__).resolve().parents[1]
    for p in sorted(root.rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    for lib in LIBRARIES:
        try:
            h.update(f"{lib}={importlib.metadata.version(lib)}".encode())
        except importlib.metadata.PackageNotFoundError:
            h.update(f"{lib}=none".encode())
    return h.hexdigest()


def _trusted(obj) -> bool:
    module = getattr(obj, "__module__", None) or ""
    name = getattr(obj, "__qualname__", "")
    return (module.startswith(TRUSTED) or module in ("builtins",)) and "<" not in name


def describe(obj, static: bool = False) -> str:
    """A description of `obj` that is the same in every process and differs whenever the
    program it enters could: arrays by shape and dtype (and by their values in a static
    field of a module, which the program holds as constants), functions and classes by module
    and name (fwid's, or a library's: their code is in `_environment`), containers and
    `equinox.Module`s field by field. Raises `_Unkeyable` for anything else."""
    if obj is None or isinstance(obj, (bool, int, float, complex, str, bytes)):
        return f"{type(obj).__name__}:{obj!r}"
    if isinstance(obj, (jax.Array, np.ndarray, np.generic)):
        weak = getattr(obj, "weak_type", False)
        out = f"array{tuple(np.shape(obj))}:{np.dtype(obj.dtype)}:{weak}"
        if static:
            out += ":" + hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest()
        return out
    if isinstance(obj, (list, tuple)):
        return f"{type(obj).__name__}[" + ",".join(describe(x, static) for x in obj) + "]"
    if isinstance(obj, dict):
        return "dict{" + ",".join(f"{describe(k, static)}={describe(obj[k], static)}"
                                  for k in sorted(obj, key=repr)) + "}"
    if isinstance(obj, Mesh):
        return f"mesh{obj.devices.shape}{obj.axis_names}:{jax.process_count()}"
    if isinstance(obj, (types.FunctionType, types.BuiltinFunctionType, type)):
        if not _trusted(obj):
            raise _Unkeyable(repr(obj))
        return f"fn:{obj.__module__}.{obj.__qualname__}"
    if isinstance(obj, eqx.Module) or dataclasses.is_dataclass(obj):
        if not _trusted(type(obj)):
            raise _Unkeyable(repr(type(obj)))
        fields = ",".join(
            f"{f.name}={describe(getattr(obj, f.name), static or f.metadata.get('static', False))}"
            for f in dataclasses.fields(obj))
        return f"{type(obj).__module__}.{type(obj).__qualname__}({fields})"
    raise _Unkeyable(f"{type(obj)!r}")


def _path(fn, args, kw) -> Path | None:
    folder = cache_folder(os.environ)
    if folder is None or jax.process_count() > 1:
        return None
    try:
        desc = describe((args, kw))
    except _Unkeyable:
        return None
    key = hashlib.sha256("|".join(
        (_environment(), f"{fn.__module__}.{fn.__qualname__}",
         f"x64={jax.config.jax_enable_x64}", jax.default_backend(), desc)).encode())
    return folder / "exported" / f"{fn.__name__.strip('_')}-{key.hexdigest()[:32]}.jaxexport"


def call(fn, args: tuple, sharded: tuple[bool, ...] = (), mesh: Mesh | None = None, **kw):
    """`fn(*args, **kw)` (`fn` a jitted function of arrays and static values, `kw` static;
    with a device `mesh`, `fn(*args, mesh=mesh, **kw)`), through its kept program when there
    is one, else kept now. `sharded`: which of `args` are split over the mesh's `"flights"`
    axis (the others replicated)."""
    if mesh is not None:
        kw = {"mesh": mesh, **kw}
    path = _path(fn, args, kw)
    if path is None:
        return fn(*args, **kw)
    dyn, static = eqx.partition(args, eqx.is_array)
    leaves, treedef = jax.tree.flatten(dyn)
    runner = _RUNNERS.get(path)
    if runner is None:
        exported = _load(path)
        if exported is None:
            def flat(*ls):
                return fn(*eqx.combine(jax.tree.unflatten(treedef, ls), static), **kw)

            try:  # a program with a host callback (EQX_ON_ERROR=raise) cannot be exported
                exported = jax.export.export(jax.jit(flat))(*leaves)
            except Exception:  # noqa: BLE001 - traced as before (any real error raised there)
                return fn(*args, **kw)
            _keep(path, exported)
        if mesh is None:
            runner = jax.jit(exported.call)
        else:
            split = [s for arg, s in zip(args, sharded)
                     for _ in jax.tree.leaves(eqx.filter(arg, eqx.is_array))]
            runner = jax.jit(exported.call, in_shardings=tuple(
                NamedSharding(mesh, PartitionSpec("flights") if s else PartitionSpec())
                for s in split))
        _RUNNERS[path] = runner
    return runner(*leaves)


#: The kept programs already loaded by this process, ready to call, by file: a second call
#: neither reads the file nor lowers the program again.
_RUNNERS: dict = {}


def _load(path: Path):
    """The kept program in `path`, or `None` (none yet, or unreadable: traced again)."""
    if not path.exists():
        return None
    try:
        return jax.export.deserialize(bytearray(path.read_bytes()))
    except Exception:  # noqa: BLE001 - an unreadable entry is traced again
        return None


def _keep(path: Path, exported) -> None:
    """Write `exported` to `path` whole or not at all (processes may share the folder); a
    read-only folder or a missing `flatbuffers` only means it is not kept."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(exported.serialize())
        os.replace(tmp, path)
    except (OSError, ImportError):
        pass
