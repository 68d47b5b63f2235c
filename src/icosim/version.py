"""The package's version, as installed (``0+unknown`` when run from a source tree that is not installed)."""

from __future__ import annotations

from functools import cache

__all__ = ["package_version"]


@cache
def package_version() -> str:
    """The version of the installed ``icosim`` distribution."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("icosim")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"
