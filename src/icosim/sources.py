"""Which source files of the package a module or script rests on: its transitive ``icosim`` imports.

Snakemake does not see the modules a job's script imports.  The workflow lists
them as inputs (``workflow/rules/common.smk``), so that editing a module reruns
exactly the jobs whose code imports it, directly or through other modules.
The imports are read from the source with :mod:`ast` (nothing is imported):
absolute and relative imports anywhere in a file, ``from package import
module`` included, and the ``__init__.py`` of every package on the way.

The pendulum's claims rest on its check kinds, not on its co-simulation:

>>> root = Path(__file__).resolve().parents[1]
>>> files = [p.relative_to(root).as_posix() for p in module_closure(["icosim.pendulum.replication.checks"], root)]
>>> "icosim/pendulum/names.py" in files, "icosim/pendulum/problem.py" in files
(True, False)
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

__all__ = ["module_closure", "script_closure", "module_path"]

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


def _imported(tree, package: str, root: Path) -> set[str]:
    """Module names (of this package) imported anywhere in ``tree``; ``package`` resolves relative imports."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1])
                base = f"{base}.{node.module}" if node.module else base
            else:
                base = node.module or ""
            out.add(base)
            for alias in node.names:  # `from package import module`
                if module_path(f"{base}.{alias.name}", root) is not None:
                    out.add(f"{base}.{alias.name}")
    return {n for n in out if n == PACKAGE or n.startswith(PACKAGE + ".")}


def _with_parents(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[: i + 1]) for i in range(len(parts))]


def module_closure(modules, root) -> list[Path]:
    """Files of ``modules`` (dotted names) and of everything they import from the package, sorted."""
    root = Path(root)
    todo = [n for m in modules for n in _with_parents(m)]
    seen, files = set(), set()
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        path = module_path(name, root)
        if path is None:
            continue
        files.add(path)
        stat = path.stat()
        for imported in _module_imports(name, path, root, stat.st_mtime_ns, stat.st_size):
            todo += _with_parents(imported)
    return sorted(files)


@cache
def _module_imports(name: str, path: Path, root: Path, mtime_ns: int, size: int) -> frozenset[str]:
    """_imported of one module file, parsed once per version of the file.

    The workflow asks for the closure of every rule's script, and those closures share most
    modules: without the cache Snakemake's start parsed about 1200 files (5 CPU-s) for 35 scripts.
    """
    tree = ast.parse(path.read_text(), filename=str(path))
    return frozenset(_imported(tree, _package_of(name, path), root))


def script_closure(script, root) -> list[Path]:
    """Package files a script (not itself part of the package) imports, directly or indirectly."""
    tree = ast.parse(Path(script).read_text(), filename=str(script))
    return module_closure(sorted(_imported(tree, "", Path(root))), root)
