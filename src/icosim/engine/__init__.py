"""The engine: the coupling methods and the one macro-step algorithm that drives any co-simulation problem.

It knows no model: a problem (:mod:`icosim.problems`) meets the contract of :mod:`.problem`, and a linear
model offers its parameter points to the spectral analysis as a :class:`~.spectral.family.LinearFamily`.  It
imports nothing of icosim outside itself but :mod:`icosim.errors`, and reads no configuration, writes no
file, draws nothing.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.problem`             the problem's contract (base class) for the macro step
:mod:`.macrostep`           the one macro-step algorithm
:mod:`.run`                 the one run loop, with an observer after each step
:mod:`.residuals`           the coupling conditions, first subsystem minus second
:mod:`.methods`             the coupling methods (Baumgarte, weighted multiplier,
                            projection) and their registry ``METHODS``
:mod:`.decompositions`      ff, fd, df, dd: which coupling variables and conditions exist
:mod:`.schemes`             Jacobi and Gauss-Seidel: which subsystem leads
:mod:`.lagrange`            Lagrange extrapolation and interpolation weights, any order k
:mod:`.backends`            the arithmetics: float64 (batched), mpmath, Arb balls
:mod:`.bounds`              the largest inputs the engine accepts, time budgets
:mod:`.layout`              the array layout of batched grids
:mod:`.schema`              the registries as JSON-schema definitions
:mod:`.spectral`            the spectral radius of any linear recurrence, certified
:mod:`.control`             adaptive macro steps for any problem
==========================  ===========================================================

The package imports none of its modules: import the one you need, e.g.
``from icosim.engine.macrostep import macro_step``.
"""
