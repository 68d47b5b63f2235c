"""The spectral radius of the co-simulation recurrence (Sect. 2, Eqs. 21-23) for one configuration.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.matrix`              the amplification matrix, from the macro step itself
:mod:`.radius`              spectral radius in float64 (with an error estimate)
                            and at any precision (mpmath)
:mod:`.certified`           proven enclosures of the spectral radius (Arb balls)
:mod:`.batched`             the certificates of a panel's points in one batch
:mod:`.policy`              the precision policy: float64, proofs where it
                            cannot decide; the verdict of every point
==========================  ===================================================

Every study asks this package for rho: the stability panels (:mod:`icosim.studies.stability`), the
convergence study's stability marks and floor-free errors, the pendulum's linearised point,
``icosim rho`` and ``icosim advise``.  Importing it loads no xarray and no matplotlib.
"""

from .certified import SpectralCertificate, certify_spectral_radius
from .matrix import amplification_matrix
from .policy import Certification, StabilityResult, spectral_radius
from .radius import spectral_radius_float64, spectral_radius_mp

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
