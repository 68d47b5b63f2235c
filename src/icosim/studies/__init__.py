"""The studies: each reads its configuration, runs problems through the engine and writes its datasets.

==========================  ===========================================================
package                     holds
==========================  ===========================================================
:mod:`.stability`           Figs. 9-20: stability panels over the parameter plane
:mod:`.convergence`         Figs. 21-23: errors and orders over macro-step sizes
:mod:`.pendulum`            Figs. 6-8: the double pendulum's runs, summary, claims
:mod:`.trade`               the pendulum's speed-accuracy trade (beyond the paper)
:mod:`.fmi`                 the coupling methods on FMU units against the built-in models
:mod:`.peers`               work-precision of icosim against the other masters on the
                            same unit files
==========================  ===========================================================

A study imports no other study: what two studies share lives below them.  The package imports none of its
modules.
"""
