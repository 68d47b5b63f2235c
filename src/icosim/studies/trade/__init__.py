"""The pendulum's speed-accuracy trade (beyond the paper): what a configuration costs for the accuracy it reaches.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.measures`            the record of one run: errors, drift, CPU, counts
:mod:`.sweep`               error over the macro step H, every configuration
:mod:`.orders`              orders over H above the pendulum's error floor
:mod:`.linear_study`        what the linear test model predicts: orders, limits
:mod:`.stability_limit`     the largest stable H, measured and predicted
:mod:`.tolerance`           error over the links' Radau tolerance at fixed H
:mod:`.adaptive`            adaptive against fixed H at equal error
:mod:`.baselines`           the monolithic baselines and the linear model's
                            errors over H
:mod:`.work_precision`      co-simulation against the monolithic pendulum, per
                            accuracy level
:mod:`.conclusions`         the rows and counts behind the report's conclusions
==========================  ===================================================

The study rests on the pendulum's model, integrator and runs (:mod:`icosim.problems.pendulum`), the
step-size control (:mod:`icosim.engine.control`) and the order fit (:mod:`icosim.order_fit`); it
imports no other study.  The package imports none of its modules.
"""
