"""One FMU instance of a scene: checked against what the scene asks of it, opened the way the FMI standard says,
stepped, saved and restored.

Only fmpy talks to the FMU (imported when a unit is opened), through one adapter per version of the standard
(:mod:`icosim.problems.fmu.fmi`: FMI 2.0 and FMI 3.0 over fmpy's documented methods), every call inside the
supervisor's record (:mod:`icosim.problems.fmu.guard`).  A unit reads and writes only the variables its
scene names (:data:`ROLES`), each with the setter and getter of its own type, in SI (:mod:`icosim.problems.fmu.measures`
converts declared units).  Start values are checked before any call and set with fmpy's
``apply_start_values`` in the state the standard allows (:mod:`icosim.problems.fmu.variables`).  Over a macro step the
unit's coupling input is a polynomial in the local time ``tau = (t - T_N)/H``; :meth:`Unit.step` hands it to the
FMU either exactly, as its value and derivatives at ``T_N`` (``fmi2SetRealInputDerivatives``, units that declare
``canInterpolateInputs``), or as ``substeps`` sub-steps each with the polynomial's value at its midpoint (every
other unit; docs/fmi.md).  Every error about a unit carries what the unit logged.

A pythonfmu unit's library is released before the interpreter exits (:mod:`icosim.problems.fmu.pythonfmu`): left to the
process's exit, pythonfmu (0.6.4 to 0.7.0 at least) frees its interpreter state twice (docs/fmi.md).
"""

from __future__ import annotations

import collections
import contextlib
import math
import tempfile
from pathlib import Path

import numpy as np

from . import guard, pythonfmu
from .description import check_kind, read_description
from .drives import DRIVE_KEYS
from .errors import FmuError, UnitStepError
from .fmi import adapter
from .measures import measure
from .variables import VariableTable

__all__ = ["Unit", "ROLES", "ENTRIES"]

_STATUS = {0: "ok", 1: "warning", 2: "discard", 3: "error", 4: "fatal", 5: "pending"}

#: Scene key -> (what it names, causalities it may have).
ROLES = {
    "position": ("the position output", ("output",)),
    "velocity": ("the velocity output", ("output",)),
    "acceleration": ("the acceleration output", ("output",)),
    "force": ("the coupling-force input", ("input",)),
    "acceleration_input": ("the prescribed-acceleration input", ("input",)),
    "position_input": ("the prescribed-position input", ("input",)),
    "velocity_input": ("the prescribed-velocity input", ("input",)),
    "reaction_force": ("the output of the force the drive exerts", ("output",)),
    "set_position": ("a tunable parameter or input that sets the position (projection)", ("parameter", "input")),
    "set_velocity": ("a tunable parameter or input that sets the velocity (projection)", ("parameter", "input")),
    "signal_input": ("a connection's input", ("input",)), "signal_output": ("a connection's output", ("output",))}  # fmt: skip


#: Entries of keys set together: a drive's inputs, the projection's, a joint unit's coupling and connections' inputs.
ENTRIES = {"drive": DRIVE_KEYS, "projected": ("set_position", "set_velocity"),
           "coupled": ("force", "acceleration_input", "signal_input")}  # fmt: skip


def _listed(names) -> list:
    """A scene entry naming one variable or a list of them (the components of a vector), as a list."""
    return list(names) if isinstance(names, (list, tuple)) else [names]


class Unit:
    """One instance of an FMU, checked and opened with its start values at ``t0``.

    Parameters
    ----------
    label : the subsystem's name in the scene (the instance name).
    path : the ``.fmu`` file.
    names : scene key (:data:`ROLES`) -> variable name, or list of names (the components of a vector quantity);
        an FMI 3.0 array element is named ``y[2]``.
    start : start values (variable name -> value), checked by :class:`~icosim.problems.fmu.variables.VariableTable`.
    inputs : ``"auto"`` (derivatives where the unit can interpolate inputs, else sub-steps), ``"derivatives"``
        or ``"substeps"``.
    substeps : sub-steps per macro step where the input is sampled.

    Counters: :attr:`do_steps`, :attr:`saved`, :attr:`restored`, :attr:`warnings`.
    """

    def __init__(self, label, path, names, start, *, inputs="auto", substeps=16, t0=0.0):
        self.label, self.path = label, Path(path)
        self.md, self.description_problems = read_description(label, self.path)
        md = self.md
        self._check_kind(md)
        self.fmi3 = md.fmiVersion.startswith("3.")
        self.table = table = VariableTable(label, md, start)
        self.start_values = table.start_values(start)
        self.elements, self.factors, self.measures = {}, {}, {}
        for key, ns in names.items():
            els = [table.element(key, n) for n in _listed(ns)]
            for el in els:
                _check_role(label, key, el.variable)
            self.elements[key] = els
            self.measures[key] = [measure(label, md, key, el.variable) for el in els]
            self.factors[key] = np.array([m.factor for m in self.measures[key]])
        self.parts = {}  # the entries (ENTRIES) of keys the unit names
        for entry, keys in ENTRIES.items():
            parts = tuple(k for k in keys if k in self.elements)
            if parts and (entry != "coupled" or (len(parts) == 2 and parts[-1] == "signal_input")):
                self.parts[entry] = parts
                self.elements[entry] = [el for k in parts for el in self.elements[k]]
                self.factors[entry] = np.concatenate([self.factors[k] for k in parts])
        self.drive_keys, self.projected_keys = self.parts.get("drive", ()), self.parts.get("projected", ())
        self.interpolates = bool(getattr(md.coSimulation, "canInterpolateInputs", False)) and not self.fmi3
        if inputs == "derivatives" and not self.interpolates:
            raise FmuError(
                f"{label}: coupling.inputs: derivatives needs a unit that declares canInterpolateInputs "
                f"(FMI 2.0); {self.path.name} does not: use inputs auto or substeps"
            )
        self.exact_inputs = self.interpolates and inputs != "substeps"
        self.substeps = int(substeps)
        self.names = dict(names)
        self._plans = {}  # keys -> how to read them (:meth:`_plan`)
        self._inputs = {}  # (route, key, k + 1, H) -> how the input is handed to the unit (:meth:`_input_plan`)
        self.do_steps = self.saved = self.restored = self.warnings = self.check_steps = 0
        #: doStep's noSetFMUStatePriorToCurrentPoint on every step, not only on the final ones: a unit whose step
        #: depends on the flag (the inspection finds it) is stepped as it needs
        self.always_final = False
        #: the largest relative difference of a step repeated from a restored state (the inspection measures it)
        self.rollback_difference = float("nan")
        #: the status of a refused call (3 error, 4 fatal): after it the standard allows only freeing the
        #: instance (error) or nothing at all (fatal)
        self.failed = 0
        self.messages = collections.deque(maxlen=20)
        self.first_warning = ""
        self.t = float(t0)
        # removed on close, or at exit for a unit nobody closed
        self._unpacked = tempfile.TemporaryDirectory(prefix=f"icosim-{label}-", dir=guard.scratch_dir())
        self.index = guard.register(self)
        try:
            self._open(t0)
        except BaseException:
            self.close()
            raise

    # -- lifecycle -------------------------------------------------------------------------
    def _open(self, t0):
        from fmpy import extract
        from fmpy.simulation import apply_start_values

        md = self.md
        try:
            unzipdir = extract(str(self.path), unzipdir=self._unpacked.name)
        except Exception as exc:
            raise FmuError(f"{self.label}: cannot unpack {self.path}: {exc}") from None
        for var in md.modelVariables:  # arrays sized by the scene's structural parameters (fmpy reads .shape)
            var.shape = self.table.shapes[var.name]
        common = dict(unzipDirectory=unzipdir, modelIdentifier=self._interface(md).modelIdentifier,
                      instanceName=self.label)  # fmt: skip
        stage = "instantiated"
        opening = guard.call(self, self._instantiate[self.fmi3], self.t)
        opening.__enter__()  # left in the finally below: the record lasts exactly as long as the opening
        try:
            if self.fmi3:
                from fmpy import fmi3

                # fmpy keeps the instantiation token as guid
                self.fmu = getattr(fmi3, self._classes[1])(guid=md.guid, **common)
                self.fmi = adapter(self, self.fmu)
                self._register_release()
                self.fmu.instantiate(logMessage=self._log3)
            else:
                from fmpy import fmi2
                from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

                self.fmu = getattr(fmi2, self._classes[0])(guid=md.guid, **common)
                self.fmi = adapter(self, self.fmu)
                self._register_release()
                cb = fmi2CallbackFunctions()
                cb.logger = fmi2CallbackLoggerTYPE(self._log2)
                cb.allocateMemory, cb.freeMemory = defaultCallbacks.allocateMemory, defaultCallbacks.freeMemory
                self._callbacks = cb  # kept alive as long as the instance
                self.fmu.instantiate(callbacks=cb)
                self.fmu.setupExperiment(startTime=t0)
            structural = [s for s in self.start_values if s.state == "configuration"]
            if structural:
                stage = "configured"
                self.fmu.enterConfigurationMode()
                for s in structural:
                    self._apply(apply_start_values, s)
                self.fmu.exitConfigurationMode()
            stage = "instantiated"
            for s in self.start_values:
                if s.state == "instantiated":
                    self._apply(apply_start_values, s)
            stage = "initialised"
            if self.fmi3:
                self.fmu.enterInitializationMode(startTime=t0)
            else:
                self.fmu.enterInitializationMode()
            for s in self.start_values:
                if s.state == "initialization":
                    self._apply(apply_start_values, s)
            self.fmu.exitInitializationMode()  # co-simulation: step mode follows (FMI 3.0 without event mode)
            self._initialised()
        except FmuError:
            raise
        except Exception as exc:
            raise FmuError(f"{self.label}: could not be {stage}: {_call_text(exc)}{self.said()}") from None
        finally:
            opening.__exit__(None, None, None)

    #: the interface a unit is opened with, as the scene's ``interface`` names it
    interface = "co-simulation"
    #: fmpy's classes of the interface (FMI 2.0, FMI 3.0)
    _classes = ("FMU2Slave", "FMU3Slave")
    #: the instantiation as the supervisor's record names it (FMI 2.0, FMI 3.0)
    _instantiate = ("fmi2Instantiate", "fmi3InstantiateCoSimulation")
    #: what the check table's open row says of the unit
    opened = "co-simulation, saves and restores its state"

    def _check_kind(self, md):
        check_kind(self.label, self.path, md)

    @staticmethod
    def _interface(md):
        return md.coSimulation

    def _initialised(self):
        """After initialisation: a co-simulation unit is in step mode."""

    def _register_release(self):
        pythonfmu.register(self, self.md, self.fmu.dll)

    def _apply(self, apply_start_values, s):
        try:
            apply_start_values(self.fmu, self.md, {s.name: s.value})
        except Exception as exc:
            status = getattr(exc, "status", 0)
            self.failed = status if status in (3, 4) else 0  # after error only freeing, after fatal nothing
            raise FmuError(
                f"{self.label}: start: {s.name}: {s.setter} refused {s.text} ({s.variable.type}, set in state "
                f"{s.state}): {_call_text(exc)}{self.said()}"
            ) from None
        self.fmi.started(s.variable, s.value)

    def _log2(self, env, instance, status, category, message):  # fmpy's logger of FMI 2.0 (3.0: _log3)
        self._logged(status, message)

    _log3 = lambda self, env, status, category, message: self._logged(status, message)  # noqa: E731

    def _logged(self, status, message):
        text = message.decode(errors="replace") if message else ""
        self.messages.append(text)
        if status == 1:
            self.warnings += 1
            self.first_warning = self.first_warning or text

    def said(self) -> str:
        """What the unit logged lately, for an error message ('' if nothing)."""
        texts = [m for m in self.messages if m]
        return f" (the unit said: {' | '.join(texts)})" if texts else ""

    def close(self):
        """Terminate and free the instance, remove its unpacked files.  A pythonfmu unit's library is released
        before fmpy closes it (:mod:`icosim.problems.fmu.pythonfmu`), also after a fatal status, which leaves it loaded."""
        fmi, self.fmu, self.fmi = getattr(self, "fmi", None), None, None
        release = pythonfmu.take(self)
        if fmi is not None and not self.failed:
            with contextlib.suppress(Exception):
                fmi.terminate()
        if release is not None:
            release()  # while the library is loaded: fmpy's dlclose may unload it
        if fmi is not None and self.failed < 4:
            with contextlib.suppress(Exception):
                fmi.free_instance()
        guard.unregister(self)
        self._unpacked.cleanup()

    def checked(self):
        """The checks before the run are done: the counters start again (their steps are kept apart)."""
        self.check_steps += self.do_steps
        self.do_steps = self.saved = self.restored = 0

    # -- information -------------------------------------------------------------------------
    def info(self) -> dict:
        """Model name, GUID or instantiation token, FMI version, generation tool, input route, counters."""
        md = self.md
        return {
            "model_name": md.modelName,
            "guid": md.guid,  # FMI 3.0: the instantiation token
            "fmi_version": md.fmiVersion,
            "generation_tool": md.generationTool or "",
            "fmu": str(self.path),
            "interface": self.interface,
            "inputs": "derivatives" if self.exact_inputs else f"substeps ({self.substeps})",
            "do_step_calls": self.do_steps,
            "states_saved": self.saved,
            "states_restored": self.restored,
            "checks_do_step_calls": self.check_steps,
            "warnings": self.warnings,
            "first_warning": self.first_warning,
            "do_step_flag": "true on every step (the unit needs it)" if self.always_final else "true on final steps",
            "rollback_difference": self.rollback_difference,
        }

    # -- values -------------------------------------------------------------------------------
    def _plan(self, keys):
        """How to read the elements under ``keys``: value references (each once), how many values they hold,
        which of those are wanted, and their factors to SI."""
        els = [el for k in keys for el in self.elements[k]]
        refs, offsets, total = [], {}, 0
        for el in els:
            if el.value_reference not in offsets:
                offsets[el.value_reference] = total
                refs.append(el.value_reference)
                total += el.size
        pick = np.array([offsets[el.value_reference] + el.index for el in els])
        factors = np.concatenate([self.factors[k] for k in keys])
        plain = total == len(els) and np.array_equal(pick, np.arange(len(els)))
        return refs, total, (None if plain else pick), (None if np.all(factors == 1.0) else factors)

    def get(self, keys) -> np.ndarray:
        """Values (SI) of the variables named under ``keys`` (scene keys), shape ``(len(keys), components)``."""
        plan = self._plans.get(keys)
        if plan is None:
            plan = self._plans[keys] = self._plan(keys)
        refs, total, pick, factors = plan
        values = np.array(self.fmi.get(refs, total))
        if pick is not None:
            values = values[pick]
        if factors is not None:
            values = values * factors
        return values.reshape(len(keys), -1)

    def read(self, keys) -> list:
        """:meth:`get` as a flat list of floats (key after key, component after component)."""
        return self.get(keys).ravel().tolist()

    def set(self, key, value):
        """Set the variable(s) named under the scene key ``key`` (a number per component, SI)."""
        self._set_values(key, (np.atleast_1d(np.asarray(value, dtype=float)) / self.factors[key]).tolist())

    def _set_values(self, key, values):
        """Set ``key``'s variables to ``values`` (floats in the unit's own units, one per component)."""
        self.fmi.set(key, values)

    def get_named(self, name) -> float:
        """The value of a scalar Real/Float64 variable (or array element) named ``name``, as the unit holds it."""
        el = self.table.element("mass", name)
        return float(self.fmi.get([el.value_reference], el.size)[el.index])

    # -- states: a macro step's rollback -----------------------------------------------------------------
    def save(self):
        """The unit's FMU state, saved, and its time."""
        self.saved += 1
        return (self.fmi.get_state(), self.t)

    def restore(self, state):
        """Back to a state :meth:`save` returned, and its time."""
        self.restored += 1
        self.fmi.set_state(state[0])
        self.t = state[1]

    def free(self, state):
        """Free a state :meth:`save` returned."""
        if self.failed or self.fmu is None:
            return  # a refused step leaves only freeing the instance allowed (fmi2Error) or nothing (fmi2Fatal)
        self.fmi.free_state(state[0])

    # -- stepping -----------------------------------------------------------------------------
    def advance(self, key, rows, t, H, *, step_index, restore=None, read=None, final=False):
        """:meth:`step` after :meth:`restore` of ``restore`` where given; the variables of ``read`` read at the end
        and returned (:meth:`get`; None: nothing read)."""
        if restore is not None:
            self.restore(restore)
        self.step(key, rows, t, H, step_index=step_index, final=final)
        return None if read is None else self.get(read)

    def step(self, key, coefficients, t, H, *, step_index, final=False):
        """Advance ``[t, t + H]`` with the input(s) ``key`` following ``u(tau) = sum_m coefficients[m] tau^m``
        (SI; ``coefficients`` ``(k + 1,)``, or ``(k + 1, components)``); afterwards the inputs hold ``u(1)`` (the
        outputs that depend on them directly are those at ``t + H``).  ``final``: no state before ``t + H`` will
        be restored (doStep's ``noSetFMUStatePriorToCurrentPoint``)."""
        c = np.asarray(coefficients, dtype=float).reshape(len(coefficients), -1) / self.factors[key]
        refs, orders, values_of = self._input_plan(key, len(c), H)
        values = (values_of @ c).tolist()  # what the input is set to, row after row; the last: u(1)
        if self.exact_inputs:
            self._set_values(key, values[0])
            if orders:  # every order up to k, zeros too: a unit may keep the derivatives of the step before
                self.fmi.set_input_derivatives(refs, orders, [v for row in values[1:-1] for v in row])
            self._do_step(t, H, step_index, final)
        else:
            n = self.substeps
            for j in range(n):
                self._set_values(key, values[j])
                self._do_step(t + j * H / n, H / n, step_index, final)
        self._set_values(key, values[-1])
        self.t = t + H

    def _input_plan(self, key, rows, H):
        """How ``key`` takes a polynomial of ``rows`` coefficients over ``H``: the input derivatives' references and
        orders, and the matrix of the values set from the coefficients (the value at ``T_N`` and ``m! c_m / H^m``,
        ``m = 1 .. k``; or the value at each sub-step's midpoint), ``u(1)`` last.  Made once per route."""
        route = (self.exact_inputs, self.substeps, key, rows, H)
        plan = self._inputs.get(route)
        if plan is None:
            if self.exact_inputs:
                refs = self.fmi.refs(key)
                scales = np.array([math.factorial(m) / H**m for m in range(1, rows)])
                matrix = np.vstack([np.eye(rows)[:1], np.eye(rows)[1:] * scales[:, None]])
                plan = (refs * (rows - 1), [m for m in range(1, rows) for _ in refs], matrix)
            else:
                tau = (np.arange(self.substeps) + 0.5) / self.substeps
                plan = ([], [], tau[:, None] ** np.arange(rows))
            plan = self._inputs[route] = (*plan[:2], np.vstack([plan[2], np.ones(rows)]))
        return plan

    def _do_step(self, t, h, step_index, final=False):
        self.do_steps += 1
        self.messages.clear()
        try:
            stopped = self.fmi.do_step(t, h, bool(final or self.always_final), step_index)
        except Exception as exc:  # more than a warning (None: raised without a status) ends the run
            code = getattr(exc, "status", None)
            self.failed = code if code in (3, 4) else 0
            raise UnitStepError(
                f"unit {self.label} refused macro step {step_index} at t = {t:.12g} s (doStep returned "
                f"{_STATUS.get(code, 'failure')}){self.said()}"
            ) from None
        if stopped:  # FMI 3.0: terminateSimulation or earlyReturn
            raise UnitStepError(f"unit {self.label} {stopped} in macro step {step_index} (from t = {t:.12g} s)")


def _check_role(label, key, var):
    what, causalities = ROLES[key]
    if var.causality not in causalities:
        raise FmuError(
            f"{label}: {key}: variable {var.name!r} has causality {var.causality!r}, but {key} must name "
            f"{what} (causality {' or '.join(causalities)})"
        )
    if var.causality == "parameter" and var.variability != "tunable":
        raise FmuError(f"{label}: {key}: parameter {var.name!r} is {var.variability}, it must be tunable")
    if var.type not in ("Real", "Float64"):
        raise FmuError(
            f"{label}: {key}: variable {var.name!r} is {var.type}; a coupling variable must be Real (FMI 2.0) or "
            "Float64 (FMI 3.0)"
        )


def _call_text(exc) -> str:
    """An fmpy exception as a sentence (its function and status where fmpy gives them)."""
    function, status = getattr(exc, "function", None), getattr(exc, "status", None)
    if function is not None and status is not None:
        return f"{function} returned {_STATUS.get(status, status)}"
    return str(exc) or type(exc).__name__
