"""The engine: the test model, the coupling methods and the one macro-step algorithm that drives them.

Everything a numerical result rests on, and nothing that reads a study's configuration,
writes a file or draws: the engine imports nothing of icosim outside itself but
:mod:`icosim.errors`.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.model`               the test model: the parameters of Eq. (71) and the physical
                            ones, converted both ways, validated
:mod:`.lagrange`            Lagrange extrapolation and interpolation weights, any order k
:mod:`.subsystems`          exact macro-step propagators of the single-mass subsystems
:mod:`.exact`               the exact monolithic solution and consistent starts
:mod:`.backends`            the arithmetics: float64 (batched), mpmath, Arb balls
:mod:`.bounds`              the largest inputs the engine accepts, time budgets
:mod:`.decompositions`      ff, fd, dd: which coupling variables and conditions exist
:mod:`.schemes`             Jacobi and Gauss-Seidel: which subsystem leads
:mod:`.problem`             the problem's contract (base class) for the macro step
:mod:`.linear_problem`      the linear test model as a co-simulation problem
:mod:`.macrostep`           the one macro-step algorithm and a whole simulation
:mod:`.methods`             the coupling methods (Baumgarte, weighted multiplier,
                            projection) and their registry ``METHODS``
==========================  ===========================================================

The package imports none of its modules: import the one you need, e.g.
``from icosim.engine.macrostep import macro_step``.
"""
