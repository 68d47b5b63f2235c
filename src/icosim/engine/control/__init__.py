"""Macro-step size control: a room any co-simulation problem can use (beyond the paper).

Co-simulation masters offer step-size control for explicit coupling (PyFMI's
master, libcosim); for the implicit, constraint-coupled schemes of the paper
none does.  This package adds it around the same macro step
(:func:`icosim.engine.macrostep.macro_step`, unchanged), as diffrax keeps
solver, step-size controller and terms apart:

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.controller`          the error estimates (predictor against corrector;
                            ECCO's power residual) and the PI step-size
                            controller with rejection
:mod:`.driver`              the adaptive loop: macro steps of varying size up
                            to an end time, for any problem that can change
                            its macro step (``set_macro_step``)
==========================  ===================================================

The double pendulum's adaptive run (:func:`icosim.problems.pendulum.runs.run_adaptive`)
is the driver with the pendulum's divergence bounds, its drift criterion and
its stored series.  The package imports none of its modules.
"""
