"""What the engine couples: each problem meets the contract of :class:`icosim.engine.problem.CosimulationProblem`.

==========================  ===========================================================
package                     holds
==========================  ===========================================================
:mod:`.linear`              the linear two-mass test model of the paper, integrated
                            exactly, and its spectral analysis (the floor the other
                            problems may map onto)
:mod:`.pendulum`            the planar double pendulum of Sect. 4
:mod:`.fmu`                 FMI co-simulation units of the user's own
==========================  ===========================================================

The problems import nothing of each other but :mod:`.linear`.  The package imports none of its modules.
"""
