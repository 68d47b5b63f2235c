"""The linear two-mass test model of the paper (Sect. 2, Eq. 71), integrated exactly.

==========================  ===========================================================
module                      holds
==========================  ===========================================================
:mod:`.model`               the test model: the parameters of Eq. (71) and the physical
                            ones, converted both ways, validated
:mod:`.subsystems`          exact macro-step propagators of the single-mass subsystems
:mod:`.exact`               the exact monolithic solution and consistent starts
:mod:`.problem`             the model as a co-simulation problem (batched)
:mod:`.family`              its parameter points for the engine's spectral analysis
:mod:`.spectral`            the spectral analysis by the model's parameters
==========================  ===========================================================

The package imports none of its modules.
"""
