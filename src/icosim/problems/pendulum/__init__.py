"""The planar double pendulum of Sect. 4 as a co-simulation problem.

Two rigid links, link 1 pinned to ground (subsystem 1) and link 2 free
(subsystem 2), coupled at a joint; the same macro step as for the linear model
(:func:`icosim.engine.macrostep.macro_step`) drives them.  The model, its sign
conventions, the displacement/displacement formulation, the sensitivities and
the projection are described in ``docs/pendulum.md``.

==========================  =====================================================
module                      holds
==========================  =====================================================
:mod:`.model`               parameters, joint points and the joint constraint
:mod:`.links`               the two links as subsystems (force or kinematically driven)
:mod:`.problem`             :class:`~.problem.PendulumCosimulation`, the problem
:mod:`.manifold`            the mass-weighted projection onto the constraint (step 4)
:mod:`.integrator`          the links' integrator: Radau IIA compiled with numba
:mod:`.reference`           the monolithic model, reference solution, consistent history
:mod:`.linearised`          the pendulum's point in the linear test model (Sect. 3)
:mod:`.runs`                a whole run (fixed or adaptive macro steps) up to the end
                            time, divergence or failure
:mod:`.names`               names of runs, series, coupling variables and datasets
:mod:`.config`              a ``pendulum:`` configuration, checked before any job
==========================  =====================================================

Two studies rest on these modules and import nothing of each other: the replication of Figs. 6-8
(:mod:`icosim.studies.pendulum`) and the speed-accuracy trade (:mod:`icosim.studies.trade`).

The package imports none of its modules: import the one you need, e.g.
``from icosim.problems.pendulum.runs import run_cosimulation``.
"""
