"""The work-precision study against the peers: icosim beside libcosim (libcosimpy, fixed step and ECCO), Ecos
(ecospy) and FMPy's ``simulate_ssp`` on the same unit files -- OSP's quarter truck and OMSimulator's
DualMassOscillator -- each master run as its users run it.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.masters`             which masters are installed here, or why one is not
:mod:`.runners`             each master's run of the unit files: its end values and
                            doStep calls
:mod:`.timing`              a run's wall time: the minimum of timed runs after a warm-up
:mod:`.config`              its systems and series, checked before any job; the runs
:mod:`.study`               one system's runs against its reference, as a dataset
:mod:`.fastest`             the datasets read back: the fastest run per error level,
                            where icosim does not win and what the runs' time goes to
:mod:`.checks`              the check kinds of its claims
==========================  ===========================================================

The package imports none of its modules.
"""
