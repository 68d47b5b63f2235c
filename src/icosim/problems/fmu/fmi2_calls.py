"""A unit's FMI 2.0 calls of the macro step, made without numpy: the value references, buffers and factors of
each read, write and input-derivatives call built once, the calls made to the functions of the unit's library as
fmpy loaded them (``fmu.dll``, argument and result types set by fmpy).  fmpy's methods of the same names wrap each
call in two Python calls, which for a small unit cost more than the call itself; the status is checked as fmpy
checks it, and fmpy would log the calls only with a call logger, which no unit has.  FMI 3.0 units and units
stepped in sub-steps take :class:`~icosim.problems.fmu.units.Unit`'s general path."""

from __future__ import annotations

import math

import numpy as np

from . import guard
from .floats import summed

__all__ = ["Fmi2Calls", "refused"]

_GET, _SET = guard.code("get"), guard.code("set")
_DO_STEP, _DERIVATIVES = guard.code("doStep"), guard.code("setRealInputDerivatives")
_FACTORIAL = [math.factorial(m) for m in range(16)]  # k is at most icosim.engine.bounds.MAX_K


def refused(function, status):
    """An FMI 2.0 call that returned more than a warning, raised as fmpy raises it."""
    from fmpy.fmi1 import FMICallException

    raise FMICallException(function=function, status=status)


class Fmi2Calls:
    """The macro step's reads, writes and steps of a :class:`~icosim.problems.fmu.units.Unit` (a mixin: it uses
    the unit's instance, index, time, elements, factors and general methods)."""

    def read(self, keys) -> list:
        """:meth:`get` as a flat list of floats (key after key, component after component): the macro step's
        read, without numpy.  An FMI 2.0 unit reads into a buffer made once per ``keys``."""
        fast = self._reads.get(keys)
        if fast is None:
            if self.fmi3 or self.fmu is None:
                return self.get(keys).ravel().tolist()
            fast = self._reads[keys] = self._read_plan(keys)
        vr, n, buf, pick, factors = fast
        fmu = self.fmu
        guard.enter(self.index, _GET, self.t)
        status = fmu.dll.fmi2GetReal(fmu.component, vr, n, buf)
        guard.leave()
        if status > 1:
            refused("fmi2GetReal", status)
        values = buf[:n]
        if pick is not None:
            values = [values[j] for j in pick]
        if factors is not None:
            values = [v * f for v, f in zip(values, factors)]
        return values

    def _read_plan(self, keys):
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference

        refs, total, pick, factors = self._plan(keys)
        n = len(refs)
        return (
            (fmi2ValueReference * n)(*refs),
            n,
            (fmi2Real * n)(),
            None if pick is None else pick.tolist(),
            None if factors is None else factors.tolist(),
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
        out = self._writes[key] = ((fmi2ValueReference * n)(*refs), n, (fmi2Real * n)(), self.factors[key].tolist())
        self._si[key] = all(f == 1.0 for f in out[3])
        return out

    def _write(self, key, values):
        """Set ``key``'s variables to ``values`` (floats in the unit's own units, one per component; FMI 2.0)."""
        vr, n, buf, _ = self._writes.get(key) or self._writer(key)
        buf[:n] = values
        fmu = self.fmu
        guard.enter(self.index, _SET, self.t)
        status = fmu.dll.fmi2SetReal(fmu.component, vr, n, buf)
        guard.leave()
        if status > 1:
            refused("fmi2SetReal", status)

    def advance(self, key, rows, t, H, *, step_index):
        """:meth:`step` with the coefficients as rows of floats (``rows[m][q]``, SI); an FMI 2.0 unit that takes
        input derivatives is driven without numpy: the same calls with the same values."""
        if not self.exact_inputs or self.fmi3:
            return self.step(key, np.array(rows, dtype=float), t, H, step_index=step_index)
        plan = self._drives.get((key, len(rows), H))
        if plan is None:
            plan = self._drives[key, len(rows), H] = self._drive_plan(key, len(rows), H)
        vr, n, buf, factors, refs, order, values, terms = plan
        # in the unit's own units; a factor of 1 divides exactly, so SI values pass as they are
        c = rows if factors is None else [[v / f for v, f in zip(row, factors)] for row in rows]
        fmu, self.t = self.fmu, t
        comp, library = fmu.component, fmu.dll
        # the guard's records of the four calls written here (guard.batch); every one names the macro step
        rec = guard.batch(self.index, t, step_index, 4 if terms else 3)
        if rec is not None:
            r, number = rec
            r[2] = _SET
            r[0] = number
        buf[:n] = c[0]
        status = library.fmi2SetReal(comp, vr, n, buf)
        if rec is not None:
            r[0] = 0.0
        if status > 1:
            refused("fmi2SetReal", status)
        if terms:  # every order up to k, zeros too: a unit may keep the derivatives of the step before
            values[:] = [factorial * c[m][q] / h_m for q, m, factorial, h_m in terms]
            if rec is not None:
                number += 1.0
                r[2] = _DERIVATIVES
                r[0] = number
            status = library.fmi2SetRealInputDerivatives(comp, refs, len(terms), order, values)
            if rec is not None:
                r[0] = 0.0
            if status > 1:
                refused("fmi2SetRealInputDerivatives", status)
        self.do_steps += 1
        self.messages.clear()
        if rec is not None:
            number += 1.0
            r[2] = _DO_STEP
            r[0] = number
        status = library.fmi2DoStep(comp, t, H, False)  # what fmpy's doStep calls
        if rec is not None:
            r[0] = 0.0
        if status > 1:
            self._steprefused(status, t, step_index)
        buf[:n] = summed(c)
        if rec is not None:
            r[2] = _SET
            r[0] = number + 1.0
        status = library.fmi2SetReal(comp, vr, n, buf)
        if rec is not None:
            r[0] = 0.0
        if status > 1:
            refused("fmi2SetReal", status)
        self.t = t + H

    def _drive_plan(self, key, rows, H):
        """What :meth:`advance` needs for a step of ``H`` with ``rows`` coefficients of ``key``, made once: its
        write (value references, their number, a buffer), the factors to the unit's units (None: all 1), and the
        input derivatives' call (value references, orders, a buffer, and per value its component, order, ``m!``
        and ``H^m``)."""
        from fmpy.fmi2 import fmi2Integer, fmi2Real, fmi2ValueReference

        vr, n, buf, factors = self._writes.get(key) or self._writer(key)
        pairs = [(q, m) for m in range(1, rows) for q in range(n)]
        size = len(pairs)
        return (
            vr,
            n,
            buf,
            None if self._si[key] else factors,
            (fmi2ValueReference * size)(*[vr[q] for q, _ in pairs]),
            (fmi2Integer * size)(*[m for _, m in pairs]),
            (fmi2Real * size)(),
            [(q, m, _FACTORIAL[m], H**m) for q, m in pairs],
        )
