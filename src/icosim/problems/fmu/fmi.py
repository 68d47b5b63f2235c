"""A unit's FMI calls: one adapter per version of the standard, over fmpy's documented API.

:class:`Fmi2` speaks FMI 2.0 through fmpy's ``FMU2Slave`` and ``FMU2Model`` (``getReal``, ``setReal``,
``setRealInputDerivatives``, ``doStep``, ``getFMUstate``, ``setFMUstate``, ``freeFMUstate``, ...), :class:`Fmi3`
FMI 3.0 through ``FMU3Slave`` and ``FMU3Model`` (``getFloat64``, ``setFloat64``, ``doStep``, ``getFMUState``, ...).
Both offer the same methods to :class:`~icosim.problems.fmu.units.Unit`, which knows no version: what differs
between the two standards (the calls' names, FMI 3.0's arrays, its doStep's early return) is said here once.

Every call is made inside the supervisor's record (``with guard.call(unit, name, t)``:
:mod:`icosim.problems.fmu.guard`), under the standard's name of the call, so a unit that hangs or crashes in it is
named.  fmpy checks each call's status and raises ``FMICallException`` (its function and status) for anything
worse than a warning.
"""

from __future__ import annotations

import numpy as np

from . import guard
from .variables import declared_start, family

__all__ = ["Fmi2", "Fmi3", "adapter", "refused"]


def refused(function, status):
    """A call that returned more than a warning, raised as fmpy raises it (for calls made on fmpy's library
    functions themselves)."""
    from fmpy.fmi1 import FMICallException

    raise FMICallException(function=function, status=status)


def adapter(unit, fmu):
    """The adapter of ``unit``'s standard (``unit.fmi3``) over its fmpy instance ``fmu``."""
    return (Fmi3 if unit.fmi3 else Fmi2)(unit, fmu)


class Fmi2:
    """The FMI 2.0 calls of one instance (``fmu``: fmpy's ``FMU2Slave`` or ``FMU2Model``) of ``unit`` (whose
    supervisor slot and time the records name)."""

    #: the calls' names, as the standard and the supervisor's records name them
    GET, SET, DO_STEP = "fmi2GetReal", "fmi2SetReal", "fmi2DoStep"
    GET_STATE, SET_STATE, FREE_STATE = "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate"
    TERMINATE, FREE_INSTANCE = "fmi2Terminate", "fmi2FreeInstance"

    def __init__(self, unit, fmu):
        self.unit, self.fmu = unit, fmu
        self._refs = {}  # scene key -> the value references of its variables

    def refs(self, key) -> list:
        """The value references of the variables ``unit`` names under the scene key ``key``."""
        refs = self._refs.get(key)
        if refs is None:
            refs = self._refs[key] = [el.value_reference for el in self.unit.elements[key]]
        return refs

    def get(self, refs, total) -> list:
        """The values of the variables ``refs`` (``total`` values in all: a scalar each in FMI 2.0)."""
        with guard.call(self.unit, self.GET, self.unit.t):
            return self.fmu.getReal(refs)

    def set(self, key, values):
        """Set the variables named under the scene key ``key`` to ``values`` (floats, the unit's own units)."""
        with guard.call(self.unit, self.SET, self.unit.t):
            self.fmu.setReal(self.refs(key), values)

    def started(self, variable, value):
        """A start value set before the run (FMI 2.0 has no arrays: nothing to keep)."""

    def set_input_derivatives(self, refs, orders, values):
        """``fmi2SetRealInputDerivatives``: the ``orders``-th derivatives of the inputs ``refs``."""
        with guard.call(self.unit, "fmi2SetRealInputDerivatives", self.unit.t):
            self.fmu.setRealInputDerivatives(refs, orders, values)

    def directional(self, unknowns, knowns, seed) -> list:
        """``sum_k d unknowns / d knowns[k] seed[k]`` (value references; the unit's own units), without a step."""
        with guard.call(self.unit, "fmi2GetDirectionalDerivative", self.unit.t):
            return self.fmu.getDirectionalDerivative(unknowns, knowns, seed)

    def do_step(self, t, h, final, step_index):
        """``fmi2DoStep`` over ``[t, t + h]`` (``final``: noSetFMUStatePriorToCurrentPoint); None (FMI 2.0 has no
        early return: a unit that stops says so by its status)."""
        with guard.call(self.unit, self.DO_STEP, t, step_index):
            self.fmu.doStep(t, h, noSetFMUStatePriorToCurrentPoint=final)

    # the FMU state's calls: fmpy names them getFMUState, setFMUState, freeFMUState in both versions (in FMI 2.0
    # the aliases of getFMUstate, setFMUstate, freeFMUstate), so both adapters share them, under their own names
    def get_state(self):
        with guard.call(self.unit, self.GET_STATE, self.unit.t):
            return self.fmu.getFMUState()

    def set_state(self, state):
        with guard.call(self.unit, self.SET_STATE, self.unit.t):
            self.fmu.setFMUState(state)

    def free_state(self, state):
        with guard.call(self.unit, self.FREE_STATE, self.unit.t):
            self.fmu.freeFMUState(state)

    def terminate(self):
        with guard.call(self.unit, self.TERMINATE, self.unit.t):
            self.fmu.terminate()

    def free_instance(self):
        with guard.call(self.unit, self.FREE_INSTANCE, self.unit.t):
            self.fmu.freeInstance()  # then fmpy unloads the library


class Fmi3(Fmi2):
    """The FMI 3.0 calls of one instance (``FMU3Slave`` or ``FMU3Model``).  An array variable is set whole: its
    value as last set is kept, an element written into it."""

    GET, SET, DO_STEP = "fmi3GetFloat64", "fmi3SetFloat64", "fmi3DoStep"
    GET_STATE, SET_STATE, FREE_STATE = "fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState"
    TERMINATE, FREE_INSTANCE = "fmi3Terminate", "fmi3FreeInstance"

    def __init__(self, unit, fmu):
        super().__init__(unit, fmu)
        self._arrays = {}  # array variable name -> its whole value (float64), as last set

    def get(self, refs, total) -> list:
        with guard.call(self.unit, self.GET, self.unit.t):
            return self.fmu.getFloat64(refs, total)

    def set(self, key, values):
        els = self.unit.elements[key]
        with guard.call(self.unit, self.SET, self.unit.t):
            if all(el.size == 1 for el in els):
                self.fmu.setFloat64(self.refs(key), values)
                return
            for el, v in zip(els, values):
                if el.size == 1:
                    self.fmu.setFloat64([el.value_reference], [v])
                    continue
                whole = self._arrays.get(el.variable.name)
                if whole is None:
                    whole = self._arrays[el.variable.name] = declared_start(el.variable, el.size)
                whole[el.index] = v
                self.fmu.setFloat64([el.value_reference], whole.tolist())

    def started(self, variable, value):
        """A start value set before the run: an array's whole value is kept (a Float64 one)."""
        if variable.shape and family(variable.type) == "real":
            self._arrays[variable.name] = np.asarray(value, dtype=float)

    def set_input_derivatives(self, refs, orders, values):  # pragma: no cover - the unit never asks
        raise NotImplementedError("FMI 3.0 units are driven by sub-steps here (no input derivatives)")

    def do_step(self, t, h, final, step_index):
        """``fmi3DoStep``; where the unit stops the simulation or returns early, what it did (else None)."""
        with guard.call(self.unit, self.DO_STEP, t, step_index):
            _, terminate, early, last = self.fmu.doStep(t, h, noSetFMUStatePriorToCurrentPoint=final)
        if terminate:
            return "asked to terminate the simulation"
        if early:
            return f"returned early at t = {last:.12g} s"
        return None
