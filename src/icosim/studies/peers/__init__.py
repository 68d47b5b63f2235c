"""The work-precision study against the peers: icosim beside libcosim (libcosimpy, fixed step and ECCO), Ecos
(ecospy) and FMPy's ``simulate_ssp`` on the same unit files -- OSP's quarter truck and OMSimulator's
DualMassOscillator -- each master run as its users run it.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.masters`             which masters are installed here, or why one is not
:mod:`.runners`             each master's run of the unit files: its end values and
                            doStep calls
==========================  ===========================================================

The package imports none of its modules.
"""
