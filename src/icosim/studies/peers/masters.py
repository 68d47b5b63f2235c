"""The masters the peers study runs beside icosim, and which of them are installed here.

A master that cannot be imported is not dropped: :func:`installed` gives the reason in its place, and a study
row names it.
"""

from __future__ import annotations

import importlib
import importlib.metadata

__all__ = ["PEER_PACKAGES", "MASTER_PACKAGES", "installed", "available"]

#: The other masters of the ``peers`` extra -> the package that brings each (Ecos loads TBB's shared library).
PEER_PACKAGES = {"libcosimpy": "libcosim", "ecospy": "Ecos"}
#: Every master -> its package.
MASTER_PACKAGES = {"icosim": "icosim", "FMPy": "fmpy", **{m: p for p, m in PEER_PACKAGES.items()}}


def installed() -> dict:
    """Master -> its package's version, or ``missing: <package> (<why the import failed>)``."""
    found = {}
    for master, package in MASTER_PACKAGES.items():
        try:
            importlib.import_module(package)
            found[master] = importlib.metadata.version(package)
        except (ImportError, OSError) as exc:
            found[master] = f"missing: {package} ({type(exc).__name__}: {exc})"
    return found


def available(versions: dict, master: str) -> bool:
    return not str(versions[master]).startswith("missing")
