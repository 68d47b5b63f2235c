"""Stability of the co-simulation recurrence (Sect. 2, Eqs. 21-23).

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.matrix`              the amplification matrix, from the macro step itself
:mod:`.spectral`            spectral radius in float64 (with an error estimate)
                            and at any precision (mpmath)
:mod:`.certified`           proven enclosures of the spectral radius (Arb balls)
:mod:`.policy`              the precision policy: float64, proofs where it
                            cannot decide; the verdict of every point
:mod:`.panels`              one panel of Figs. 9-20 as a dataset (xarray)
:mod:`.checks`              the stability claims' check kinds
==========================  ===================================================

Importing this package loads the first three only (no xarray, no matplotlib).
"""

from .certified import SpectralCertificate, certify_spectral_radius
from .matrix import amplification_matrix
from .policy import Certification, StabilityResult, spectral_radius
from .spectral import spectral_radius_float64, spectral_radius_mp

__all__ = [
    "amplification_matrix",
    "spectral_radius_float64",
    "spectral_radius_mp",
    "spectral_radius",
    "StabilityResult",
    "Certification",
    "certify_spectral_radius",
    "SpectralCertificate",
]
