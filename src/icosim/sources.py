"""Which source files of the package a module or script rests on: its transitive ``icosim`` imports.

Snakemake does not see the modules a job's script imports.  The workflow gives
each job the :func:`library_digest` of them as a parameter
(``workflow/rules/common.smk``), so that editing a module reruns exactly the
jobs whose code imports it, directly or through other modules.
The imports are read from the source with :mod:`ast` (nothing is imported):
absolute and relative imports anywhere in a file, ``from package import
module`` included, and the ``__init__.py`` of every package on the way.

The pendulum's claims rest on its check kinds, not on its co-simulation:

>>> root = Path(__file__).resolve().parents[1]
>>> files = [p.relative_to(root).as_posix() for p in module_closure(["icosim.studies.pendulum.checks"], root)]
>>> "icosim/problems/pendulum/names.py" in files, "icosim/problems/pendulum/problem.py" in files
(True, False)
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import tempfile
from functools import cache
from pathlib import Path

__all__ = ["module_closure", "script_closure", "module_path", "library_digest"]

PACKAGE = "icosim"


def module_path(name: str, root: Path) -> Path | None:
    """The file of module ``name`` (``a.b`` -> ``a/b.py`` or ``a/b/__init__.py``) under ``root``, if any."""
    base = Path(root, *name.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _package_of(name: str, path: Path) -> str:
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


def _import_names(tree, package: str) -> tuple[list[str], list[str]]:
    """``(names, candidates)`` of the imports anywhere in ``tree``: the modules named, and the
    ``package.name`` of each ``from package import name`` (a module if such a file exists)."""
    names, candidates = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1])
                base = f"{base}.{node.module}" if node.module else base
            else:
                base = node.module or ""
            names.add(base)
            candidates.update(f"{base}.{alias.name}" for alias in node.names)
    return sorted(_ours(names)), sorted(_ours(candidates))


def _ours(names):
    return {n for n in names if n == PACKAGE or n.startswith(PACKAGE + ".")}


def _imported(names: tuple[list[str], list[str]], root: Path) -> set[str]:
    """Module names (of this package) among ``names`` (:func:`_import_names`), the candidates that are modules."""
    plain, candidates = names
    return set(plain) | {c for c in candidates if module_path(c, root) is not None}


def _with_parents(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[: i + 1]) for i in range(len(parts))]


def module_closure(modules, root) -> list[Path]:
    """Files of ``modules`` (dotted names) and of everything they import from the package, sorted.

    A module that is not there -- asked for, or imported by one of them -- is an error
    (:class:`ModuleNotFoundError` naming it and who wants it): a closure without it would vouch for less
    than it says."""
    root = Path(root)
    todo = [(n, None) for m in modules for n in _with_parents(m)]
    seen, files = set(), set()
    while todo:
        name, importer = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        path = module_path(name, root)
        if path is None:
            who = f"imported by {importer}" if importer else "asked for"
            raise ModuleNotFoundError(f"no module {name} under {root} ({who})", name=name)
        files.add(path)
        stat = path.stat()
        for imported in _module_imports(name, path, root, stat.st_mtime_ns, stat.st_size):
            todo += [(n, name) for n in _with_parents(imported)]
    return sorted(files)


@cache
def _module_imports(name: str, path: Path, root: Path, mtime_ns: int, size: int) -> frozenset[str]:
    """The package modules one module file imports, read once per version of the file.

    The workflow asks for the closure of every rule's script, and those closures share most
    modules: without this cache Snakemake's start parsed about 1200 files (5 CPU-s) for 35 scripts.
    """
    return frozenset(_imported(_source_imports(path, _package_of(name, path)), root))


def script_closure(script, root) -> list[Path]:
    """Package files a script (not itself part of the package) imports, directly or indirectly."""
    return module_closure(sorted(_imported(_source_imports(Path(script), ""), Path(root))), root)


def library_digest(files, root) -> str:
    """SHA-256 over the paths (relative to ``root``) and contents of ``files``: a job's parameter.

    A parameter, not a list of inputs: Snakemake reruns a job whose parameters changed, as it does
    one whose input is newer, and the scheduler does not stat the ~100 files of every waiting
    job at each step (a twentieth of a full run's CPU).  Content, not time stamps, decides: a
    checkout that only touches a file reruns nothing.
    """
    digest = hashlib.sha256()
    root = Path(root)
    for path in sorted(root / f for f in files):  # a relative name is relative to root
        stat = path.stat()
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(_file_sha256(path, stat.st_mtime_ns, stat.st_size).encode())
    return digest.hexdigest()


@cache
def _file_sha256(path: Path, mtime_ns: int, size: int) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# -- the imports of a source text, kept across processes ----------------------------------------
# Snakemake reads the workflow again in every process that runs it (each test's dry run, each
# cluster job), and parsing the package's sources is a third of that.  What a text imports depends
# on the text and its package only, so it is kept by the text's SHA-256 in one JSON file of the
# user's cache directory; any problem with that file means parsing as if it were not there.
_CACHE_VERSION = 1


def _cache_file() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path(os.path.expanduser("~"), ".cache")
    return Path(base) / "icosim" / f"source-imports-v{_CACHE_VERSION}.json"


@cache
def _disk_cache() -> dict:
    try:
        data = json.loads(_cache_file().read_text())
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def _source_imports(path: Path, package: str) -> tuple[list[str], list[str]]:
    """:func:`_import_names` of the file at ``path`` (``package`` resolves its relative imports)."""
    text = path.read_bytes()
    key = f"{package}:{hashlib.sha256(text).hexdigest()}"
    known = _disk_cache().get(key)
    if isinstance(known, list) and len(known) == 2 and all(isinstance(v, list) for v in known):
        return known[0], known[1]
    names = _import_names(ast.parse(text, filename=str(path)), package)
    _remember(key, names)
    return names


def _remember(key: str, names) -> None:
    """Add one entry to the cache file: read, merge, replace atomically (a concurrent writer may win)."""
    cached = _disk_cache()
    cached[key] = list(names)
    target = _cache_file()
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            on_disk = json.loads(target.read_text())
            cached.update((k, v) for k, v in on_disk.items() if k not in cached)
        except (OSError, ValueError, AttributeError):
            pass
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=target.name, suffix=".part")
        with os.fdopen(fd, "w") as fh:
            json.dump(cached, fh)
        os.replace(tmp, target)
    except OSError:
        pass
