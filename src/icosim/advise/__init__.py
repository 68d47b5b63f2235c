"""Is my coupled system stable?  Every configuration for one physical two-mass system.

A user brings two subsystems -- masses ``m1, m2`` [kg], stiffnesses ``c1, c2``
[N/m], dampers ``d1, d2`` [N s/m] (overdamped ones included) -- and either a
macro step ``H`` [s] or a range of them.  :func:`advise` answers, for every
registered coupling method (:data:`icosim.engine.methods.METHODS`), each index it can
be formulated at, each decomposition it is defined for, each approximation
order ``k`` and each coupling scheme (:data:`icosim.engine.schemes.SCHEMES`: Jacobi, and
Gauss-Seidel with subsystem 1 or subsystem 2 first; the variants when asked for):

* at one ``H``: the spectral radius ``rho`` of the co-simulation recurrence
  (the precision policy of :func:`icosim.problems.linear.spectral.spectral_radius`: float64,
  certified in ball arithmetic where float64 cannot decide) and the verdict;
* over a range ``[H_lo, H_hi]``: where the configuration is stable.  Stability need
  not be monotone in ``H`` (the weighted multiplier at ``k = 2`` is unstable
  for small ``H`` and stable for larger ones), so the range is first scanned
  on a grid of log-spaced ``H``, then every stable/unstable transition between
  neighbouring grid points is refined by bracketing (multisection, each pass
  one batched call) until the bracket is ``rtol`` wide.  The result is the
  stable intervals; the *largest stable H* is the upper end of the last one.
  Intervals narrower than the grid spacing can be missed, and the output says
  so.

The answer is a :class:`pandas.DataFrame`, one row per configuration (its label in
the column ``configuration``), stable ones ranked first (at one ``H`` by ``rho``: the smaller, the faster a coupling error
decays per macro step; over a range first the configurations stable from the range's
lower end, by how far up they stay stable, then those stable only on higher
intervals, by their largest stable ``H``).  ``df.attrs`` holds the system, its dimensionless parameters
(Eq. 71, or the per-unit-mass coefficients when a subsystem is overdamped) and
the settings.

The dimensionless parameters (Eq. 6, 71) of the two-mass system: with
``m1 = 1, c1 = 100, d1 = 2`` and ``H = 0.01`` s, ``lr1 = -d1 H/(2 m1) = -0.01``
and ``li1 = H sqrt(c1/m1 - (d1/(2 m1))^2)``:

>>> system = TwoMassSystem(m1=1, m2=2, c1=100, c2=200, d1=2, d2=4)
>>> p = system.dimensionless(0.01)
>>> round(p["lr1"], 12), round(p["li1"], 6), p["am21"], p["alr21"], p["ali21"]
(-0.01, 0.099499, 2.0, 1.0, 1.0)

Method parameters are taken in physical units (Baumgarte ``mu`` in s); one
not given is 1 in the paper's dimensionless form (``mu_bar = mu/H = 1``,
``a = b = 1``), as in Figs. 9-15.

A coupling scheme, method or decomposition added to its registry is ranked here with no
change: configurations are enumerated by :func:`configurations` from the registries,
every spectral radius is computed by :func:`evaluate`, and the ``verdict`` column is the
one place a verdict is stated.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.core`                the system, the configurations, one evaluation
:mod:`.scan`                stable intervals over an H range, the answer table
:mod:`.output`              the answer as text and JSON records, the progress bar
:mod:`.maps`                ``icosim map``: stability maps on demand with the
                            stability study's panel code (not imported here: it
                            loads xarray and matplotlib)
==========================  ===================================================
"""

from .core import DEFAULT_K, VERDICTS, Configuration, Evaluation, TwoMassSystem, configurations, evaluate
from .output import Progress, advice_records, advice_text
from .scan import DEFAULT_RTOL, DEFAULT_SCAN, advise, check_settings, stable_intervals

__all__ = [
    "TwoMassSystem",
    "Configuration",
    "Evaluation",
    "VERDICTS",
    "configurations",
    "evaluate",
    "stable_intervals",
    "advise",
    "check_settings",
    "advice_records",
    "advice_text",
    "Progress",
    "DEFAULT_K",
    "DEFAULT_SCAN",
    "DEFAULT_RTOL",
]
