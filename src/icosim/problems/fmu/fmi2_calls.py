"""A unit's FMI 2.0 calls of the macro step, made without numpy: the value references, buffers and factors of
each read, write and input-derivatives call built once, the calls made to the functions of the unit's library as
fmpy loaded them (``fmu.dll``; reads, writes and input derivatives with their ctypes arguments built once, through
the same functions without declared argument types: :func:`_direct`).  fmpy's methods of the same names wrap each
call in two Python calls, which for a small unit cost more than the call itself; the status is checked as fmpy
checks it, and fmpy would log the calls only with a call logger, which no unit has.  FMI 3.0 units and units
stepped in sub-steps take :class:`~icosim.problems.fmu.units.Unit`'s general path."""

from __future__ import annotations

import ctypes
import math

import numpy as np

from . import guard
from .floats import summed

__all__ = ["Fmi2Calls", "refused"]

_FACTORIAL = [math.factorial(m) for m in range(16)]  # k is at most icosim.engine.bounds.MAX_K


def _direct(fmu, name):
    """The function ``name`` of the unit's library as fmpy declared it, and the same function with no argument
    types, to be called with ctypes objects of the declared types built once (then ctypes converts nothing, most
    of a small call's cost).  A call takes the second only while the library's attribute is still the first (not
    wrapped, e.g. by a benchmark recording the calls)."""
    library = fmu.dll
    declared = getattr(library, name)
    if not hasattr(declared, "argtypes"):  # wrapped already: every call goes to the wrapper
        return None, None
    return declared, ctypes.CDLL(library._name, handle=library._handle)[name]


def _read_values(fast, status) -> list:
    """The values of a read (:meth:`Fmi2Calls._get_real`) as floats in SI, or the call refused."""
    if status > 1:
        refused("fmi2GetReal", status)
    _, n, buf, pick, factors, *_ = fast
    values = buf[:n]
    if pick is not None:
        values = [values[j] for j in pick]
    if factors is not None:
        values = [v * f for v, f in zip(values, factors)]
    return values


def refused(function, status):
    """An FMI 2.0 call that returned more than a warning, raised as fmpy raises it."""
    from fmpy.fmi1 import FMICallException

    raise FMICallException(function=function, status=status)


class Fmi2Calls:
    """The macro step's reads, writes, steps and saved states of a :class:`~icosim.problems.fmu.units.Unit` (a
    mixin: it uses the unit's instance, index, time, elements, factors and general methods)."""

    # -- states: a macro step's rollback (what fmpy's getFMUstate, setFMUstate and freeFMUstate do) ----------
    def save(self):
        """The unit's FMU state, saved, and its time."""
        self.saved += 1
        if self.fmi3:
            with guard.call(self, "fmi3GetFMUState", self.t):
                state = self.fmu.getFMUState()
        else:
            state = self._new_state()
            with guard.call(self, "fmi2GetFMUstate", self.t):
                status = self._state_call("fmi2GetFMUstate", ctypes.byref(state))
            if status > 1:
                refused("fmi2GetFMUstate", status)
        return (state, self.t)

    def restore(self, state):
        """Back to a state :meth:`save` returned, and its time."""
        self.restored += 1
        if self.fmi3:
            with guard.call(self, "fmi3SetFMUState", self.t):
                self.fmu.setFMUState(state[0])
        else:
            with guard.call(self, "fmi2SetFMUstate", self.t):
                status = self._state_call("fmi2SetFMUstate", state[0])
            if status > 1:
                refused("fmi2SetFMUstate", status)
        self.t = state[1]

    def free(self, state):
        """Free a state :meth:`save` returned."""
        if self.failed or self.fmu is None:
            return  # a refused step leaves only freeing the instance allowed (fmi2Error) or nothing (fmi2Fatal)
        if self.fmi3:
            with guard.call(self, "fmi3FreeFMUState", self.t):
                self.fmu.freeFMUState(state[0])
        else:
            with guard.call(self, "fmi2FreeFMUstate", self.t):
                status = self._state_call("fmi2FreeFMUstate", ctypes.byref(state[0]))
            if status > 1:
                refused("fmi2FreeFMUstate", status)

    def _state_call(self, name, argument):
        """The status of the library's state function ``name`` called on the instance with ``argument``: without
        declared argument types, the instance as a ctypes argument made once (:func:`_direct`)."""
        direct = self._states.get(name)
        if direct is None:
            direct = self._states[name] = (*_direct(self.fmu, name), ctypes.c_void_p(self.fmu.component))
        declared, bare, component = direct
        f = getattr(self.fmu.dll, name)
        return bare(component, argument) if f is declared else f(self.fmu.component, argument)

    def read(self, keys) -> list:
        """:meth:`get` as a flat list of floats (key after key, component after component): the macro step's
        read, without numpy.  An FMI 2.0 unit reads into a buffer made once per ``keys``."""
        fast = self._reads.get(keys)
        if fast is None:
            if self.fmi3 or self.fmu is None:
                return self.get(keys).ravel().tolist()
            fast = self._reads[keys] = self._read_plan(keys)
        with guard.call(self, "fmi2GetReal", self.t):
            status = self._get_real(fast)
        return _read_values(fast, status)

    def _get_real(self, fast):
        """``fmi2GetReal`` of a read made once (:meth:`_read_plan`) into its buffer; its status."""
        vr, n, buf, _, _, declared, bare, args = fast
        f = self.fmu.dll.fmi2GetReal
        return bare(*args) if f is declared else f(self.fmu.component, vr, n, buf)

    def _read_plan(self, keys):
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference

        refs, total, pick, factors = self._plan(keys)
        n = len(refs)
        vr, buf = (fmi2ValueReference * n)(*refs), (fmi2Real * n)()
        return (
            vr,
            n,
            buf,
            None if pick is None else pick.tolist(),
            None if factors is None else factors.tolist(),
            *_direct(self.fmu, "fmi2GetReal"),
            (ctypes.c_void_p(self.fmu.component), vr, ctypes.c_size_t(n), buf),
        )

    def put(self, key, values):
        """:meth:`set` from a list of floats (SI, one per component), without numpy for an FMI 2.0 unit."""
        if self.fmi3:
            return self.set(key, values)
        factors = (self._writes.get(key) or self._writer(key))[3]
        self._write(key, values if self._si[key] else [v / f for v, f in zip(values, factors)])

    def _writer(self, key):
        """An FMI 2.0 unit's write of ``key``: value references, their number and a buffer, made once."""
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference

        refs = [el.value_reference for el in self.elements[key]]
        n = len(refs)
        vr, buf, component = (fmi2ValueReference * n)(*refs), (fmi2Real * n)(), ctypes.c_void_p(self.fmu.component)
        out = self._writes[key] = (
            vr, n, buf, self.factors[key].tolist(), *_direct(self.fmu, "fmi2SetReal"),
            (component, vr, ctypes.c_size_t(n), buf),
        )  # fmt: skip
        self._si[key] = all(f == 1.0 for f in out[3])
        return out

    def _write(self, key, values):
        """Set ``key``'s variables to ``values`` (floats in the unit's own units, one per component; FMI 2.0)."""
        vr, n, buf, _, declared, bare, args = self._writes.get(key) or self._writer(key)
        buf[:n] = values
        fmu = self.fmu
        f = fmu.dll.fmi2SetReal
        with guard.call(self, "fmi2SetReal", self.t):
            status = bare(*args) if f is declared else f(fmu.component, vr, n, buf)
        if status > 1:
            refused("fmi2SetReal", status)

    def advance(self, key, rows, t, H, *, step_index, restore=None, read=None, final=False):
        """:meth:`step` with the coefficients as rows of floats (``rows[m][q]``, SI); an FMI 2.0 unit that takes
        input derivatives is driven without numpy: the same calls with the same values (``final`` as there).  With ``restore``, the
        unit first returns to that saved state (:meth:`restore`); with ``read``, the variables of those keys are
        read at the end (:meth:`read`) and returned; the calls recorded as one sequence (:func:`guard.calls`)."""
        if not self.exact_inputs or self.fmi3:
            if restore is not None:
                self.restore(restore)
            self.step(key, np.array(rows, dtype=float), t, H, step_index=step_index, final=final)
            return None if read is None else self.read(read)
        fast = None
        if read is not None:
            fast = self._reads.get(read)
            if fast is None:
                fast = self._reads[read] = self._read_plan(read)
        plan = self._drives.get((key, len(rows), H))
        if plan is None:
            plan = self._drives[key, len(rows), H] = self._drive_plan(key, len(rows), H)
        vr, n, buf, factors, refs, order, values, terms, direct = plan
        set_declared, set_bare, set_args, derivatives_declared, derivatives_bare, derivatives_args = direct
        # in the unit's own units; a factor of 1 divides exactly, so SI values pass as they are
        c = rows if factors is None else [[v / f for v, f in zip(row, factors)] for row in rows]
        fmu, self.t = self.fmu, t
        comp, library = fmu.component, fmu.dll
        sequence = guard.calls(self, t, step_index)  # every call recorded, naming the macro step
        try:
            if restore is not None:
                self.restored += 1
                sequence.now("fmi2SetFMUstate")
                status = self._state_call("fmi2SetFMUstate", restore[0])
                if status > 1:
                    refused("fmi2SetFMUstate", status)
            buf[:n] = c[0]
            f = library.fmi2SetReal
            sequence.now("fmi2SetReal")
            status = set_bare(*set_args) if f is set_declared else f(comp, vr, n, buf)
            if status > 1:
                refused("fmi2SetReal", status)
            if terms:  # every order up to k, zeros too: a unit may keep the derivatives of the step before
                values[:] = [factorial * c[m][q] / h_m for q, m, factorial, h_m in terms]
                f = library.fmi2SetRealInputDerivatives
                sequence.now("fmi2SetRealInputDerivatives")
                if f is derivatives_declared:
                    status = derivatives_bare(*derivatives_args)
                else:
                    status = f(comp, refs, len(terms), order, values)
                if status > 1:
                    refused("fmi2SetRealInputDerivatives", status)
            self.do_steps += 1
            self.messages.clear()
            sequence.now("fmi2DoStep")
            # noSetFMUStatePriorToCurrentPoint: true where no state before t + H will be restored
            status = library.fmi2DoStep(comp, t, H, final or self.always_final)  # what fmpy's doStep calls
            if status > 1:
                self._steprefused(status, t, step_index)
            buf[:n] = summed(c)
            f = library.fmi2SetReal
            sequence.now("fmi2SetReal")
            status = set_bare(*set_args) if f is set_declared else f(comp, vr, n, buf)
            if status > 1:
                refused("fmi2SetReal", status)
            self.t = t + H
            if fast is None:
                return None
            sequence.now("fmi2GetReal")
            status = self._get_real(fast)
        finally:
            sequence.end()
        return _read_values(fast, status)

    def _drive_plan(self, key, rows, H):
        """What :meth:`advance` needs for a step of ``H`` with ``rows`` coefficients of ``key``, made once: its
        write (value references, their number, a buffer), the factors to the unit's units (None: all 1), and the
        input derivatives' call (value references, orders, a buffer, and per value its component, order, ``m!``
        and ``H^m``)."""
        from fmpy.fmi2 import fmi2Integer, fmi2Real, fmi2ValueReference

        vr, n, buf, factors, *write = self._writes.get(key) or self._writer(key)
        pairs = [(q, m) for m in range(1, rows) for q in range(n)]
        size = len(pairs)
        refs, order = (
            (fmi2ValueReference * size)(*[vr[q] for q, _ in pairs]),
            (fmi2Integer * size)(*[m for _, m in pairs]),
        )
        values, component = (fmi2Real * size)(), ctypes.c_void_p(self.fmu.component)
        derivatives = (component, refs, ctypes.c_size_t(size), order, values)
        return (
            vr,
            n,
            buf,
            None if self._si[key] else factors,
            refs,
            order,
            values,
            [(q, m, _FACTORIAL[m], H**m) for q, m in pairs],
            (*write, *_direct(self.fmu, "fmi2SetRealInputDerivatives"), derivatives),
        )
