"""The links' integrator: batched Radau IIA and its numba transcription (only the pendulum uses it).

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.radau`               batched Radau IIA (scipy's algorithm, one shared
                            step sequence for a batch of initial values)
:mod:`.compiled`            the same algorithm for the two links, compiled with
                            numba
:mod:`.systems`             the compiled integrator from Python: a link, the
                            result and the error of an integration
:mod:`.tableau`             the constants of Radau IIA and its step-size control
:mod:`.compiled_step`       a link's part of a macro step (input, integration,
                            outputs) in one compiled call
:mod:`.compiled_links`      the links' right-hand sides and outputs as numba
                            kernels
:mod:`.compiled_algebra`    the small linear algebra the kernels inline
:mod:`.kernel_cache`        numba's disk cache of the kernels: kept valid, filled
                            once
==========================  ===================================================

The package imports none of its modules.
"""
