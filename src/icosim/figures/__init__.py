"""Figure builders: they take datasets and draw, never recompute.

Every builder returns a :class:`matplotlib.figure.Figure` (no global pyplot
state), so callers choose how to save it; :func:`save_figure` writes PNG and
PDF atomically.
"""

from __future__ import annotations

from pathlib import Path

from ..datasets import atomic_path

__all__ = ["save_figure", "stability_figure"]


def save_figure(fig, *paths, dpi: int = 110):
    """Write ``fig`` to each path; the format follows the suffix (``.png``, ``.pdf``)."""
    for path in paths:
        fmt = Path(path).suffix.lstrip(".").lower()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi, metadata=_metadata(fmt))


def _metadata(fmt):
    from .. import __version__

    if fmt == "pdf":  # no creation date: identical inputs give identical files
        return {"Creator": f"icosim {__version__}", "CreationDate": None}
    if fmt == "png":
        return {"Software": f"icosim {__version__}"}
    return None


from .stability import stability_figure  # noqa: E402
