"""Projection (Sects. 2.1.3, 2.2.3, 2.3.1): one solve on acceleration level, then the projection.

After the corrector the problem projects positions and velocities onto the
constraint manifold (mass-weighted, Eq. 30).  No parameters; index 1, every
decomposition.

>>> projection().solves, projection().projection
(((1, (0, 0, 1)),), True)
"""

from __future__ import annotations

from .base import CouplingMethod, MethodSpec

__all__ = ["projection", "SPEC"]


def projection() -> CouplingMethod:
    """Acceleration-level correction followed by the mass-weighted projection."""
    return CouplingMethod("projection", ((1, (0, 0, 1)),), projection=True, params={"index": 1})


SPEC = MethodSpec(name="projection", label="projection", short_label="projection", build=projection)
