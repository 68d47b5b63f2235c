"""Convergence study of Sect. 3.7 (Figs. 21-23): NRMSE of Eq. (72) over macro-step sizes.

The test model is used in physical units (``m1 = 1, m2 = 2, c1 = c2 = 1000,
d1 = d2 = 10`` in the paper) with a dimensional macro step ``H`` in seconds, and
every co-simulation is compared with the exact monolithic solution
(:class:`icosim.problems.linear.exact.MonolithicSolution`) at the macro-time points.

==============================  ===================================================
module                          holds
==============================  ===================================================
:mod:`.metric`                  the NRMSE of Eq. (72) and how the garbled formula is read
:mod:`.experiment`              model, initial conditions, end time, step sizes; method
                                parameters in physical units
:mod:`.study`                   the runs over all step sizes: stepping, unstable runs
:mod:`.panels`                  figure layout: which curves form a panel dataset
:mod:`.datasets`                a panel as a NetCDF-ready dataset
:mod:`.curves`                  panel datasets read back as one record per curve
:mod:`.checks`                  the ``convergence_order`` claims
:mod:`.config`                  a ``convergence:`` configuration, checked before any job
:mod:`.work_precision`          CPU time and counted work against the error
==============================  ===================================================

The order fit over the asymptotic range is :mod:`icosim.order_fit`, shared with the pendulum's
speed-accuracy study.  The package imports none of its modules: import the one you need.
"""
