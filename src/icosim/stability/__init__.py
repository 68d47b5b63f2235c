"""Stability of the co-simulation recurrence (Sect. 2, Eqs. 21-23).

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.matrix`              the amplification matrix, from the macro step itself
:mod:`.spectral`            spectral radius in float64 (with an error estimate)
                            and at any precision (mpmath)
:mod:`.policy`              the precision policy between the two; stability
:mod:`.panels`              one panel of Figs. 9-20 as a dataset (xarray)
:mod:`.checks`              the stability claims' check kinds
==========================  ===================================================

Importing this package loads the first three only (no xarray, no matplotlib).
"""

from .matrix import amplification_matrix
from .policy import StabilityResult, is_stable, spectral_radius
from .spectral import spectral_radius_float64, spectral_radius_mp

__all__ = [
    "amplification_matrix",
    "spectral_radius_float64",
    "spectral_radius_mp",
    "spectral_radius",
    "StabilityResult",
    "is_stable",
]
