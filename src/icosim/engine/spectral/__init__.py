"""The spectral radius of a linear co-simulation recurrence (Sect. 2, Eqs. 21-23), for any linear model.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.family`              what the analysis asks of a model: a family of
                            linear problems over parameter points
:mod:`.matrix`              the amplification matrix, from the macro step itself
:mod:`.radius`              spectral radius in float64 (with an error estimate)
                            and at any precision (mpmath)
:mod:`.certified`           proven enclosures of the spectral radius (Arb balls)
:mod:`.batched`             the certificates of a panel's points in one batch
:mod:`.policy`              the precision policy: float64, proofs where it
                            cannot decide; the verdict of every point
==========================  ===================================================

The engine knows no model: the linear two-mass model offers its points as a family
(:class:`icosim.problems.linear.family.TwoMass`), and :mod:`icosim.problems.linear.spectral` takes its
parameters directly.  Importing this package loads no xarray and no matplotlib.
"""

from .certified import SpectralCertificate, certify_spectral_radius
from .family import LinearFamily
from .matrix import amplification_matrix
from .policy import Certification, StabilityResult, spectral_radius
from .radius import spectral_radius_float64, spectral_radius_mp

__all__ = [
    "LinearFamily",
    "amplification_matrix",
    "spectral_radius_float64",
    "spectral_radius_mp",
    "spectral_radius",
    "StabilityResult",
    "Certification",
    "certify_spectral_radius",
    "SpectralCertificate",
]
