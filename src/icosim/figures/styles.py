"""Line styles, markers and colours the figures share, derived from the engine's registries.

A decomposition, method or scheme added to its registry gets a style by its
place in the registry, so no figure lists the entries itself.

>>> decomposition_style("ff"), decomposition_style("dd")
(('-', 'o'), (':', '^'))
"""

from __future__ import annotations

from ..engine.decompositions import DECOMPOSITIONS
from ..engine.methods import METHODS
from ..engine.schemes import SCHEMES

__all__ = ["decomposition_style", "method_colour", "scheme_colour"]

_LINESTYLES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "D", "^", "v", "P")
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")
#: the paper's scheme (the first registered, Jacobi) grey: the reference the others are read against
_SCHEME_COLOURS = ("0.55", "tab:blue", "tab:orange", "tab:cyan", "tab:red", "tab:olive", "tab:pink")


def decomposition_style(name: str) -> tuple[str, str]:
    """``(linestyle, marker)`` of a registered decomposition by its place in the registry
    (ff solid with circles, fd dashed with squares, df dash-dotted with diamonds, dd dotted with triangles)."""
    names = list(DECOMPOSITIONS)
    i = names.index(name) if name in names else len(names)
    return _LINESTYLES[i % len(_LINESTYLES)], _MARKERS[i % len(_MARKERS)]


def method_colour(name: str) -> str:
    """Colour of a registered method (Baumgarte blue, weighted multiplier orange, projection green, ...)."""
    names = list(METHODS)
    return _COLOURS[(names.index(name) if name in names else len(names)) % len(_COLOURS)]


def scheme_colour(name: str) -> str:
    """Colour of a registered coupling scheme (Jacobi grey, Gauss-Seidel 1→2 blue, 2→1 orange, ...)."""
    names = list(SCHEMES)
    return _SCHEME_COLOURS[(names.index(name) if name in names else len(names)) % len(_SCHEME_COLOURS)]
