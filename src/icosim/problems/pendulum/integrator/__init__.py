"""The links' integrator: batched Radau IIA compiled with numba (only the pendulum uses it).

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.compiled`            batched Radau IIA (scipy's algorithm, one shared
                            step sequence for a batch of initial values) for
                            the two links and the whole pendulum, compiled
                            with numba
:mod:`.systems`             the compiled integrator from Python: a link, the
                            whole pendulum, the result and the error of an
                            integration
:mod:`.tableau`             its constants (Butcher tableau, step-size control)
:mod:`.compiled_step`       a link's part of a macro step (input, integration,
                            outputs) in one compiled call
:mod:`.compiled_links`      the links' right-hand sides and outputs (and the
                            whole pendulum's right-hand side) as numba kernels
:mod:`.compiled_algebra`    the small linear algebra the kernels inline
:mod:`.kernel_cache`        numba's disk cache of the kernels: kept valid, filled
                            once
==========================  ===================================================

The package imports none of its modules.  tests/reference_radau.py is the same algorithm in numpy,
the independent reference of the tests.
"""
