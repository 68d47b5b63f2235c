"""Figure builders: they take datasets and draw, never recompute.

Every builder returns a :class:`matplotlib.figure.Figure` (no global pyplot
state), so callers choose how to save it; :func:`save_figure` writes PNG and
PDF atomically.  The builders live in one module per part (:mod:`.stability`,
:mod:`.convergence`, :mod:`.pendulum`, :mod:`.pendulum_trade`, :mod:`.schemes`);
importing this package loads none of them.
"""

from __future__ import annotations

from pathlib import Path

from ..io.netcdf import atomic_path

__all__ = ["save_figure"]


def save_figure(fig, *paths, dpi: int = 110):
    """Write ``fig`` to each path; the format follows the suffix (``.png``, ``.pdf``).

    The layout (constrained layout, if the figure uses it) is computed for the first file and then
    kept for the others: it is in figure coordinates, so a second pass would only repeat the
    slowest part of saving (for a figure with twenty panels, about half of its time).  ``fig``'s
    layout engine is ``"none"`` afterwards.
    """
    for i, path in enumerate(paths):
        fmt = Path(path).suffix.lstrip(".").lower()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi, metadata=_metadata(fmt))
        if i == 0:
            fig.set_layout_engine("none")


def _metadata(fmt):
    from .. import __version__

    if fmt == "pdf":  # no creation date: identical inputs give identical files
        return {"Creator": f"icosim {__version__}", "CreationDate": None}
    if fmt == "png":
        return {"Software": f"icosim {__version__}"}
    return None
