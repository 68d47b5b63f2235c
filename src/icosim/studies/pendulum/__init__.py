"""The replication of Sect. 4 (Figs. 6-8): the pendulum's runs stored, summarised and checked.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.datasets`            run and reference datasets (NetCDF contract)
:mod:`.summary`             one row per run: errors, expected and observed
                            behaviour
:mod:`.checks`              the ``pendulum_stability`` claims
==========================  ===================================================

The runs themselves (:mod:`icosim.problems.pendulum.runs`), their names
(:mod:`icosim.problems.pendulum.names`) and the ``pendulum:`` configuration
(:mod:`icosim.problems.pendulum.config`) are shared with the speed-accuracy study
(:mod:`icosim.studies.trade`) and live one level up.  The package imports none of its modules.
"""
