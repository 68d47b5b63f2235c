"""One FMU instance of a scene: loaded, checked against what the scene asks of it, stepped, saved and restored.

Only fmpy talks to the FMU (imported when a unit is opened).  A unit reads and writes only the variables its
scene names (:data:`ROLES`).  Over a macro step the unit's coupling input is a polynomial in the local time
``tau = (t - T_N)/H``; :meth:`Unit.step` hands it to the FMU either exactly, as its value and derivatives at
``T_N`` (``fmi2SetRealInputDerivatives``, units that declare ``canInterpolateInputs``), or as ``substeps``
sub-steps each with the polynomial's value at its midpoint (every other unit; docs/fmi.md).

A pythonfmu unit's library is released before the interpreter exits (:func:`_pythonfmu_release`): left to the
process's exit, pythonfmu (0.6.4 to 0.7.0 at least) frees its interpreter state twice (docs/fmi.md).
"""

from __future__ import annotations

import atexit
import difflib
import itertools
import math
import shutil
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .errors import FmuError, UnitStepError

__all__ = ["Unit", "ROLES", "read_description", "check_unit"]

#: Scene key -> (what it names, causalities it may have).
ROLES = {
    "position": ("the position output", ("output",)),
    "velocity": ("the velocity output", ("output",)),
    "acceleration": ("the acceleration output", ("output",)),
    "force": ("the coupling-force input", ("input",)),
    "acceleration_input": ("the prescribed-acceleration input", ("input",)),
    "reaction_force": ("the output of the force the drive exerts", ("output",)),
    "set_position": ("a tunable parameter or input that sets the position (projection)", ("parameter", "input")),
    "set_velocity": ("a tunable parameter or input that sets the velocity (projection)", ("parameter", "input")),
}

#: Why a unit must save and restore its state: every scheme integrates a unit more than once over a macro step.
STATE_REASON = (
    "every coupling scheme integrates a unit more than once from the same macro-step start (predictor, the "
    "perturbed steps of the sensitivities, corrector), which needs fmi2GetFMUstate/fmi2SetFMUstate"
)


def read_description(label: str, path: Path):
    """The unit's model description (fmpy), or :class:`FmuError` naming ``label`` and the file."""
    from fmpy import read_model_description

    if not Path(path).is_file():
        raise FmuError(f"{label}: FMU file {path} does not exist")
    if not zipfile.is_zipfile(path):
        raise FmuError(f"{label}: {path} is not an FMU (not a ZIP archive)")
    try:
        return read_model_description(str(path), validate=True)
    except Exception as exc:  # fmpy raises plain exceptions for unreadable or invalid descriptions
        first = " ".join(str(exc).split()[:40]) or type(exc).__name__
        raise FmuError(f"{label}: {path} has no valid modelDescription.xml ({first})") from None


#: A unit's number -> the teardown of its pythonfmu library (:func:`_pythonfmu_release`), until it is closed.
_RELEASES: dict = {}
_NUMBERS = itertools.count()


def _pythonfmu_release(md, dll):
    """pythonfmu's own teardown of the library's interpreter state (``finalizePythonInterpreter``), or None for a
    unit of another exporter (or of a pythonfmu without it).

    pythonfmu keeps that state in a global ``std::shared_ptr`` of the library, freed on two paths: the global's
    C++ destructor (an exit handler registered when the library is loaded) and the library's destructor
    function, which calls ``finalizePythonInterpreter`` (it assigns ``nullptr``).  At ``dlclose`` they run in
    that safe order, but the first pythonfmu library a process loads is never unloaded (it defines
    ``STB_GNU_UNIQUE`` symbols of libstdc++, so glibc makes it NODELETE): at exit the C++ destructor frees the
    shared_ptr's control block first, then ``finalizePythonInterpreter`` releases it again and writes into the
    freed block (glibc aborts, "corrupted double-linked list", when that block sits in one of its bin lists).
    Called while the library is loaded, it empties the global, and both exit paths find nothing to free.  With
    the interpreter already running the state holds no Python object (pythonfmu then neither initialises nor
    finalises Python), no instance uses it, and an instance created later in the library makes a new one.
    """
    if not (md.generationTool or "").startswith("PythonFMU"):
        return None
    release = getattr(dll, "finalizePythonInterpreter", None)
    if release is not None:
        release.argtypes, release.restype = [], None
    return release


@atexit.register
def _release_pythonfmu_libraries():
    """Units never closed: their pythonfmu libraries released before the interpreter finalises (still loaded, as
    no unit closed them)."""
    while _RELEASES:
        _RELEASES.popitem()[1]()


def check_unit(label: str, path: Path, md, names: dict, start: dict):
    """Refuse a unit the scene cannot use: not co-simulation, no saved states, a missing variable or one of the
    wrong causality (close matches listed).  ``names``: scene key -> variable name."""
    if md.fmiVersion not in ("2.0",) and not md.fmiVersion.startswith("3."):
        raise FmuError(f"{label}: {path} is FMI {md.fmiVersion}; FMI 2.0 or 3.0 co-simulation units are supported")
    if md.coSimulation is None:
        raise FmuError(
            f"{label}: {path} is a model-exchange unit only (no <CoSimulation> in its modelDescription.xml); "
            "a scene needs co-simulation units, which bring their own solver"
        )
    if not md.coSimulation.canGetAndSetFMUstate:
        raise FmuError(f"{label}: {path} declares canGetAndSetFMUstate=false; {STATE_REASON}")
    variables = {v.name: v for v in md.modelVariables}
    for key, name in ((k, n) for k, ns in names.items() for n in _listed(ns)):
        var = _variable(label, key, name, variables)
        what, causalities = ROLES[key]
        if var.causality not in causalities:
            raise FmuError(
                f"{label}: {key}: variable {name!r} has causality {var.causality!r}, but {key} must name "
                f"{what} (causality {' or '.join(causalities)})"
            )
        if var.causality == "parameter" and var.variability != "tunable":
            raise FmuError(f"{label}: {key}: parameter {name!r} is {var.variability}, it must be tunable")
        if var.type not in ("Real", "Float64"):
            raise FmuError(f"{label}: {key}: variable {name!r} is {var.type}, it must be Real (Float64)")
    for name in start:
        var = _variable(label, "start", name, variables)
        if var.causality not in ("parameter", "input") or var.variability == "constant":
            raise FmuError(
                f"{label}: start: {name!r} has causality {var.causality!r} and variability {var.variability!r}; "
                "start values go to parameters and inputs"
            )


def _listed(names) -> list:
    """A scene entry naming one variable or a list of them (the components of a vector), as a list."""
    return list(names) if isinstance(names, (list, tuple)) else [names]


def _variable(label, key, name, variables):
    if name in variables:
        return variables[name]
    close = difflib.get_close_matches(name, list(variables), n=3, cutoff=0.5)
    hint = f"; close matches: {', '.join(close)}" if close else f"; it has {', '.join(sorted(variables)[:12])}"
    raise FmuError(f"{label}: {key}: the unit has no variable {name!r}{hint}")


class Unit:
    """One instance of an FMU, opened with its start values and ready at ``t0``.

    Parameters
    ----------
    label : the subsystem's name in the scene (the instance name).
    path : the ``.fmu`` file.
    names : scene key (:data:`ROLES`) -> variable name, or list of names (the components of a vector quantity).
    start : start values (variable name -> value).
    inputs : ``"auto"`` (derivatives where the unit can interpolate inputs, else sub-steps), ``"derivatives"``
        or ``"substeps"``.
    substeps : sub-steps per macro step where the input is sampled.

    Counters: :attr:`do_steps`, :attr:`saved`, :attr:`restored`.
    """

    def __init__(self, label, path, names, start, *, inputs="auto", substeps=16, t0=0.0):
        self.label, self.path = label, Path(path)
        self.md = md = read_description(label, self.path)
        check_unit(label, self.path, md, names, start)
        self.fmi3 = md.fmiVersion.startswith("3.")
        self.interpolates = bool(getattr(md.coSimulation, "canInterpolateInputs", False)) and not self.fmi3
        if inputs == "derivatives" and not self.interpolates:
            raise FmuError(
                f"{label}: coupling.inputs: derivatives needs a unit that declares canInterpolateInputs "
                f"(FMI 2.0); {self.path.name} does not: use inputs auto or substeps"
            )
        self.exact_inputs = self.interpolates and inputs != "substeps"
        self.substeps = int(substeps)
        variables = {v.name: v for v in md.modelVariables}
        self.vr = {key: [variables[n].valueReference for n in _listed(ns)] for key, ns in names.items()}
        self.names = dict(names)
        self.do_steps = self.saved = self.restored = 0
        #: the status of a refused call (3 error, 4 fatal): after it the standard allows only fmi2FreeInstance
        #: (error) or nothing at all (fatal)
        self.failed = 0
        self.messages = []
        self._number = next(_NUMBERS)  # its key in _RELEASES
        self._tmp = tempfile.mkdtemp(prefix=f"icosim-{label}-")
        try:
            self._open(variables, start, t0)
        except BaseException:
            self.close()
            raise

    # -- lifecycle -------------------------------------------------------------------------
    def _open(self, variables, start, t0):
        from fmpy import extract

        md = self.md
        try:
            unzipdir = extract(str(self.path), unzipdir=self._tmp)
        except Exception as exc:
            raise FmuError(f"{self.label}: cannot unpack {self.path}: {exc}") from None
        common = dict(unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=self.label)
        try:
            if self.fmi3:
                from fmpy.fmi3 import FMU3Slave

                self.fmu = FMU3Slave(guid=md.guid, **common)  # fmpy keeps the instantiation token as guid
                self._register_release()
                self.fmu.instantiate(logMessage=self._log3)
                self.fmu.enterInitializationMode(startTime=t0)
            else:
                from fmpy.fmi2 import FMU2Slave, defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

                self.fmu = FMU2Slave(guid=md.guid, **common)
                self._register_release()
                cb = fmi2CallbackFunctions()
                cb.logger = fmi2CallbackLoggerTYPE(self._log2)
                cb.allocateMemory, cb.freeMemory = defaultCallbacks.allocateMemory, defaultCallbacks.freeMemory
                self._callbacks = cb  # kept alive as long as the instance
                self.fmu.instantiate(callbacks=cb)
                self.fmu.setupExperiment(startTime=t0)
                self.fmu.enterInitializationMode()
            for name, value in start.items():
                self._set_refs([variables[name].valueReference], [float(value)])
            self.fmu.exitInitializationMode()  # co-simulation: step mode follows (FMI 3.0 without event mode)
        except FmuError:
            raise
        except Exception as exc:
            raise FmuError(f"{self.label}: {self.path.name} could not be instantiated and initialised: {exc}") from None

    def _register_release(self):
        release = _pythonfmu_release(self.md, self.fmu.dll)
        if release is not None:
            _RELEASES[self._number] = release

    def _log2(self, env, instance, status, category, message):
        self.messages.append(message.decode(errors="replace") if message else "")

    def _log3(self, env, status, category, message):
        self.messages.append(message.decode(errors="replace") if message else "")

    def close(self):
        """Terminate and free the instance, remove its unpacked files.  A pythonfmu unit's library is released
        before fmpy closes it (:func:`_pythonfmu_release`), also after a fatal status, which leaves it loaded."""
        fmu, self.fmu = getattr(self, "fmu", None), None
        release = _RELEASES.pop(getattr(self, "_number", None), None)
        if fmu is not None and not self.failed:
            try:
                fmu.terminate()
            except Exception:
                pass
        if release is not None:
            release()  # while the library is loaded: fmpy's dlclose may unload it
        if fmu is not None and self.failed < 4:
            try:
                fmu.freeInstance()  # fmi2FreeInstance, then dlclose
            except Exception:
                pass
        shutil.rmtree(self._tmp, ignore_errors=True)

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
            "inputs": "derivatives" if self.exact_inputs else f"substeps ({self.substeps})",
            "do_step_calls": self.do_steps,
            "states_saved": self.saved,
            "states_restored": self.restored,
        }

    # -- values -------------------------------------------------------------------------------
    def _set_refs(self, refs, values):
        (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(refs, values)

    def get(self, keys) -> np.ndarray:
        """Values of the variables named under ``keys`` (scene keys), shape ``(len(keys), components)``."""
        refs = [r for k in keys for r in self.vr[k]]
        values = self.fmu.getFloat64(refs) if self.fmi3 else self.fmu.getReal(refs)
        return np.array(values, dtype=float).reshape(len(keys), -1)

    def set(self, key, value):
        """Set the variable(s) named under the scene key ``key`` (a number per component)."""
        self._set_refs(self.vr[key], [float(v) for v in np.atleast_1d(value)])

    def get_named(self, name) -> float:
        var = next(v for v in self.md.modelVariables if v.name == name)
        ref = [var.valueReference]
        return float((self.fmu.getFloat64(ref) if self.fmi3 else self.fmu.getReal(ref))[0])

    # -- states -------------------------------------------------------------------------------
    def save(self):
        self.saved += 1
        return self.fmu.getFMUState() if self.fmi3 else self.fmu.getFMUstate()

    def restore(self, state):
        self.restored += 1
        (self.fmu.setFMUState if self.fmi3 else self.fmu.setFMUstate)(state)

    def free(self, state):
        if self.failed or self.fmu is None:
            return  # a refused step leaves only freeing the instance allowed (fmi2Error) or nothing (fmi2Fatal)
        (self.fmu.freeFMUState if self.fmi3 else self.fmu.freeFMUstate)(state)

    # -- stepping -----------------------------------------------------------------------------
    def step(self, key, coefficients, t, H, *, step_index):
        """Advance ``[t, t + H]`` with the input(s) ``key`` following ``u(tau) = sum_m coefficients[m] tau^m``
        (``coefficients`` ``(k + 1,)``, or ``(k + 1, components)``); afterwards the inputs hold ``u(1)`` (the
        outputs that depend on them directly are those at ``t + H``)."""
        c = np.asarray(coefficients, dtype=float).reshape(len(coefficients), -1)
        refs = self.vr[key]
        if self.exact_inputs:
            self._set_refs(refs, [float(v) for v in c[0]])
            # every order up to k, zeros too: a unit may keep the derivatives of the step before
            orders = [(ref, m) for m in range(1, c.shape[0]) for ref in refs]
            if orders:
                values = [math.factorial(m) * float(c[m, refs.index(ref)]) / H**m for ref, m in orders]
                self.fmu.setRealInputDerivatives([r for r, _ in orders], [m for _, m in orders], values)
            self._do_step(t, H, step_index)
        else:
            n = self.substeps
            for j in range(n):
                tau = (j + 0.5) / n
                self._set_refs(refs, [float(np.polyval(c[::-1, q], tau)) for q in range(c.shape[1])])
                self._do_step(t + j * H / n, H / n, step_index)
        self._set_refs(refs, [float(v) for v in c.sum(axis=0)])

    def _do_step(self, t, h, step_index):
        self.do_steps += 1
        del self.messages[:]
        try:
            result = self.fmu.doStep(t, h, noSetFMUStatePriorToCurrentPoint=False)
        except Exception as exc:
            code = getattr(exc, "status", None)
            status = {1: "warning", 2: "discard", 3: "error", 4: "fatal", 5: "pending"}.get(code, "failure")
            self.failed = code if code in (3, 4) else 0
            said = f": {' '.join(m for m in self.messages if m)}" if any(self.messages) else ""
            raise UnitStepError(
                f"unit {self.label} refused macro step {step_index} at t = {t:.12g} s (doStep returned {status}){said}"
            ) from None
        if self.fmi3 and (result[1] or result[2]):  # terminateSimulation, earlyReturn
            what = "asked to terminate the simulation" if result[1] else f"returned early at t = {result[3]:.12g} s"
            raise UnitStepError(f"unit {self.label} {what} in macro step {step_index} (from t = {t:.12g} s)")
