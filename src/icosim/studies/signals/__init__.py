"""The workflow's signal-coupling study: OMSimulator's DualMassOscillator on its Model Exchange units, coupled by
its signal connections and by a joint, against its exact solution, with the predicted spectral radius against the
growth measured on unstable runs.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.config`              its cases, checked before any job; a case's scene
:mod:`.study`               one case over H: errors, order, prediction, growth
:mod:`.checks`              the check kinds of its claims
==========================  ===========================================================

The package imports none of its modules.
"""
