"""The stability study: the panels of Figs. 9-20 over parameter grids, their datasets and claims.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.panels`              one panel of Figs. 9-20 as configured (grid, rows)
:mod:`.datasets`            one panel computed as a dataset (xarray)
:mod:`.regions`             the grid points a claim reads, the verdict masks
:mod:`.checks`              the stability claims' check kinds
:mod:`.pointwise`           the point-by-point check kind ``pointwise``
:mod:`.comparison`          stable shares of a figure under each coupling scheme
==========================  ===================================================

The spectral radius of one point (amplification matrix, float64 and mpmath,
proofs in ball arithmetic, the precision policy) is the engine's:
:mod:`icosim.engine.spectral`.  The package imports none of its modules.
"""
