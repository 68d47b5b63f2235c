"""A Model Exchange unit: its equations integrated by icosim over each macro step, so that the macro step saves
and restores the continuous states and the time, and no ``fmi2GetFMUstate`` is needed.

:class:`ExchangeUnit` has the interface of :class:`~icosim.problems.fmu.units.Unit` (``advance``, ``step``,
``save``, ``restore``, ``free``, ``get``, ``read``, ``set``): the problem, the inspection, the check and
the identification do not know which interface a unit has.  Over ``[T_N, T_N + H]`` the coupling input follows
the coupling polynomial ``u(tau) = sum_m c_m tau^m``, ``tau = (t - T_N)/H``, set at every evaluation of the
right-hand side; at the end the unit holds the end state, the time ``T_N + H`` and the input ``u(1)``, so the
outputs read there are those of the end of the step.

The integrator is scipy's ``DOP853`` (Dormand and Prince's explicit Runge-Kutta method of order 8 with its own
error control), stepped by hand (:class:`scipy.integrate.DOP853`), so that ``fmi2CompletedIntegratorStep`` is
called after every accepted step where the unit asks for it.  Why this one: every macro step starts the
integration again from a restored state (predictor, corrector, the perturbed steps of the sensitivities), and a
one-step method restarts at no cost, where a multistep method (CVODE's BDF and Adams, fmpy's
:mod:`fmpy.sundials`) starts again at order one with small steps; at the tolerances the coupling needs an order-8
method takes one or a few steps per macro step.  A stiff unit (one whose fastest mode is much faster than a
macro step) makes an explicit method take many steps: such a unit is better coupled as co-simulation.

The default relative tolerance :data:`DEFAULT_TOLERANCE` (absolute: the same times each state's nominal value)
keeps the integration error below what the coupling resolves at the macro steps the studies use, so that a run
converges with the coupling's order; a smaller one comes near the rounding of the states (docs/fmi.md).

Events are not supported: a unit that declares event indicators (``numberOfEventIndicators > 0``) is refused
when it is opened, naming the count, as is one that declares a time event after its initialisation or asks for
an event after an integrator step (a step event).  Without events a unit's discrete states do not change over
a run, so its continuous states, the time and its inputs are all a macro step needs to keep; after an event a
repeated integration would need the discrete states from before it, which only ``fmi2SetFMUstate`` restores.
"""

from __future__ import annotations

import ctypes

import numpy as np

from . import guard
from .description import read_description
from .errors import FmuError, UnitStepError
from .fmi import refused
from .units import Unit

__all__ = ["ExchangeUnit", "open_fmu_unit", "DEFAULT_TOLERANCE", "INTERFACES", "check_exchange"]

#: The integrator's relative tolerance by default (docs/fmi.md).
DEFAULT_TOLERANCE = 1e-10

#: The values of a subsystem's ``interface``.
INTERFACES = ("auto", "co-simulation", "model-exchange")


def check_exchange(label, path, md):
    """Refuse a unit that cannot be integrated here as Model Exchange: not FMI 2.0 or 3.0, without
    ``<ModelExchange>``, or with event indicators."""
    if md.fmiVersion not in ("2.0",) and not md.fmiVersion.startswith("3."):
        raise FmuError(f"{label}: {path} is FMI {md.fmiVersion}; FMI 2.0 or 3.0 model exchange units are supported")
    if md.modelExchange is None:
        raise FmuError(
            f"{label}: interface: model-exchange: {path} has no <ModelExchange> in its modelDescription.xml; use "
            "interface co-simulation or auto"
        )
    n = int(md.numberOfEventIndicators or 0)
    if n > 0:
        cs = md.coSimulation
        fix = (
            "use interface co-simulation (its own solver handles the events)"
            if cs is not None and cs.canGetAndSetFMUstate
            else "no interface of it can be coupled here"
        )
        raise FmuError(
            f"{label}: {path.name} declares {n} event indicator{'s' if n != 1 else ''} "
            f"(numberOfEventIndicators={n}); icosim integrates a model exchange unit without state events: {fix}"
        )


def open_fmu_unit(label, path, names, start, *, interface="auto", tolerance=None, inputs="auto", substeps=16,
                  t0=0.0):  # fmt: skip
    """The unit with the interface the scene asks for: ``co-simulation`` (:class:`Unit`), ``model-exchange``
    (:class:`ExchangeUnit`) or ``auto``: co-simulation where the unit can roll back (``canGetAndSetFMUstate``),
    else model exchange where it has it (else co-simulation, which refuses it naming the flag).  ``tolerance``
    is the integrator's relative tolerance of a model exchange unit; given for a co-simulation unit it is an
    error."""
    if interface not in INTERFACES:
        raise FmuError(f"{label}: interface: {interface!r} is not allowed; allowed: {', '.join(INTERFACES)}")
    chosen, why = interface, f"interface {interface}"
    if interface == "auto":
        md, _ = read_description(label, path)
        cs, me = md.coSimulation, md.modelExchange
        flag = "canGetAndSetFMUState" if md.fmiVersion.startswith("3.") else "canGetAndSetFMUstate"
        if cs is not None and cs.canGetAndSetFMUstate:
            chosen, why = "co-simulation", f"interface auto: its co-simulation can roll back ({flag})"
        elif me is not None:
            chosen = "model-exchange"
            why = (
                f"interface auto: its co-simulation cannot roll back ({flag}=false)"
                if cs is not None
                else "interface auto: it has no co-simulation"
            )
        else:
            chosen = "co-simulation"
    if chosen == "co-simulation":
        if tolerance is not None:
            raise FmuError(
                f"{label}: tolerance: is the integrator's tolerance of a model exchange unit; this unit is coupled "
                f"as co-simulation ({why}), which integrates with its own solver: remove tolerance, or set "
                "interface: model-exchange"
            )
        unit = Unit(label, path, names, start, inputs=inputs, substeps=substeps, t0=t0)
    else:
        unit = ExchangeUnit(label, path, names, start, tolerance=tolerance, t0=t0)
    unit.opened = f"{unit.opened} ({why})"
    return unit


class ExchangeUnit(Unit):
    """One instance of a Model Exchange FMU, integrated by icosim (module docstring).

    Parameters as :class:`Unit`, and ``tolerance``: the integrator's relative tolerance (None:
    :data:`DEFAULT_TOLERANCE`); the absolute tolerance of each state is the same times its nominal value.

    Counters as :class:`Unit` (:attr:`do_steps` counts integrations over a macro step), and
    :attr:`evaluations` (right-hand sides) and :attr:`integrator_steps`.
    """

    interface = "model-exchange"
    _classes = ("FMU2Model", "FMU3Model")
    _instantiate = ("fmi2Instantiate", "fmi3InstantiateModelExchange")

    def __init__(self, label, path, names, start, *, tolerance=None, t0=0.0):
        self.tolerance = DEFAULT_TOLERANCE if tolerance is None else float(tolerance)
        if not 0.0 < self.tolerance < 1.0:
            raise FmuError(f"{label}: tolerance: {tolerance!r} must lie between 0 and 1 (a relative tolerance)")
        for key in ("set_position", "set_velocity"):
            if key in names:
                raise FmuError(
                    f"{label}: {key}: a model exchange unit's state is its continuous states, which icosim does "
                    "not map to the joint's position and velocity: the projection cannot move it; use method "
                    "baumgarte or weighted (and initial: check or as-is), or interface: co-simulation"
                )
        self.evaluations = self.integrator_steps = 0
        self._held = {}  # key -> the values (the unit's own units) its input variables were last set to
        super().__init__(label, path, names, start, inputs="auto", substeps=1, t0=t0)
        self.exact_inputs = False  # the input is the polynomial itself, in the right-hand side
        self.opened = (
            f"model exchange, integrated by icosim (scipy DOP853, relative tolerance {self.tolerance:g}, "
            f"absolute {self.tolerance:g} x each state's nominal; {self.nx} continuous state"
            f"{'s' if self.nx != 1 else ''}, no events)"
        )

    # -- lifecycle ------------------------------------------------------------------------------
    def _check_kind(self, md):
        check_exchange(self.label, self.path, md)

    @staticmethod
    def _interface(md):
        return md.modelExchange

    def _initialised(self):
        """Out of initialisation: the event iteration the standard asks for (the unit's discrete states settle),
        then continuous-time mode; a time event or a request to terminate is refused."""
        fmu = self.fmu  # exitInitializationMode leaves a model exchange unit in event mode
        for _ in range(1000):
            info = fmu.updateDiscreteStates() if self.fmi3 else fmu.newDiscreteStates()
            update, terminate, _, _, defined, when = info
            if terminate:
                raise FmuError(f"{self.label}: asked to terminate the simulation right after its initialisation")
            if not update:
                break
        else:
            raise FmuError(f"{self.label}: its event iteration after initialisation did not settle (1000 rounds)")
        if defined:
            raise FmuError(
                f"{self.label}: declares a time event at t = {when:.12g} s after its initialisation; icosim "
                "integrates a model exchange unit without events: use interface co-simulation"
            )
        fmu.enterContinuousTimeMode()
        self._prepare()

    def _prepare(self):
        """The buffers and calls of the right-hand side, made once."""
        md, fmu = self.md, self.fmu
        self.nx = nx = int(md.numberOfContinuousStates or 0)
        self._nx = ctypes.c_size_t(nx)
        self._xbuf, self._dxbuf = (ctypes.c_double * max(nx, 1))(), (ctypes.c_double * max(nx, 1))()
        self._xview = np.frombuffer(self._xbuf, dtype=float)[:nx]
        self._dxview = np.frombuffer(self._dxbuf, dtype=float)[:nx]
        prefix = "fmi3" if self.fmi3 else "fmi2"
        derivatives = "fmi3GetContinuousStateDerivatives" if self.fmi3 else "fmi2GetDerivatives"
        library = fmu.dll
        self._calls = tuple(
            getattr(library, f"{prefix}{name}")
            for name in ("SetTime", "SetContinuousStates", "GetContinuousStates", "GetNominalsOfContinuousStates")
        ) + (getattr(library, derivatives),)
        self._component = fmu.component
        # FMI 2.0 completedIntegratorStepNotNeeded, FMI 3.0 needsCompletedIntegratorStep, as fmpy reads both
        self._completed = bool(md.modelExchange.needsCompletedIntegratorStep)
        nominal = np.ones(nx)
        if nx:
            self._check(f"{prefix}GetContinuousStates", self._calls[2](self._component, self._xbuf, self._nx))
            x = self._xview.copy()
            self._check(f"{prefix}GetNominalsOfContinuousStates", self._calls[3](self._component, self._xbuf, self._nx))
            nominal = np.abs(self._xview.copy())
            nominal[~(nominal > 0) | ~np.isfinite(nominal)] = 1.0
            self._xview[:] = x
        else:
            x = np.zeros(0)
        self._atol = self.tolerance * nominal
        self._x = x

    def _check(self, name, status):
        if status > 1:
            self.failed = status if status in (3, 4) else 0
            refused(name, status)

    # -- information ----------------------------------------------------------------------------
    def info(self) -> dict:
        out = super().info()
        out["inputs"] = "the coupling polynomial in the right-hand side (model exchange)"
        out["integrator"] = "scipy DOP853"
        out["tolerance"] = self.tolerance
        out["continuous_states"] = self.nx
        out["rhs_evaluations"] = self.evaluations
        out["integrator_steps"] = self.integrator_steps
        return out

    # -- the inputs the macro step keeps with the state -----------------------------------------------
    def _set_values(self, key, values):
        at = 0
        for part in self.parts.get(key, (key,)):  # an entry's keys held apart: the latest value of each is restored
            n = len(self.elements[part])
            self._held[part], at = list(values[at : at + n]), at + n
        super()._set_values(key, values)

    # -- states: the continuous states, the time and the inputs ----------------------------------------
    def save(self):
        """The unit's continuous states, its time and its inputs' values."""
        self.saved += 1
        return (self._x.copy(), self.t, dict(self._held))

    def restore(self, state):
        """Back to a state :meth:`save` returned."""
        self.restored += 1
        x, t, held = state
        self._x = x.copy()
        self._set_state(t, self._x)
        for key, values in held.items():
            if self._held.get(key) != values:
                self._set_values(key, values)
        self.t = t

    def free(self, state):
        """Nothing to free: a saved state is an array."""

    def _set_state(self, t, x):
        prefix = "fmi3" if self.fmi3 else "fmi2"
        self._check(f"{prefix}SetTime", self._calls[0](self._component, ctypes.c_double(t)))
        if self.nx:
            self._xview[:] = x
            self._check(f"{prefix}SetContinuousStates", self._calls[1](self._component, self._xbuf, self._nx))

    def derivatives(self, x, read=None) -> tuple[np.ndarray, np.ndarray | None]:
        """The derivatives of the continuous states at the states ``x``, with the unit's time and inputs as they
        stand, and the variables under the keys ``read`` there (:meth:`get`; read first: a unit may update its
        outputs only when they are asked for before its derivatives); the unit is left at ``x`` (restore it
        after).  The identification's differences."""
        prefix = "fmi3" if self.fmi3 else "fmi2"
        self.evaluations += 1
        with guard.call(self, f"{prefix}DoStep", self.t, 0):  # recorded as a step from the start
            self._x = np.array(x, dtype=float)
            self._set_state(self.t, self._x)
            values = None if read is None else self.get(read)
            if self.nx:
                self._check(f"{prefix}GetDerivatives", self._calls[4](self._component, self._dxbuf, self._nx))
        return self._dxview.copy(), values

    # -- stepping -------------------------------------------------------------------------------
    def step(self, key, coefficients, t, H, *, step_index, final=False):
        """Integrate ``[t, t + H]`` with the input(s) ``key`` following ``u(tau) = sum_m coefficients[m] tau^m``
        (SI; ``(k + 1,)`` or ``(k + 1, components)``; ``key`` None: a unit without a coupling input, its inputs
        held); afterwards the unit holds the end state, ``t + H`` and ``u(1)``."""
        from scipy.integrate import DOP853

        # its writes are calls of their own inside the integration's record (which comes back after each)
        inputs_at = self._driver(key, coefficients, t, H)

        self.do_steps += 1
        self.messages.clear()
        prefix = "fmi3" if self.fmi3 else "fmi2"
        set_time, set_states, _, _, get_derivatives = self._calls
        comp, xbuf, dxbuf, nx = self._component, self._xbuf, self._dxbuf, self._nx
        xview, dxview = self._xview, self._dxview

        def rhs(tt, x):
            self.evaluations += 1
            inputs_at(tt)
            self._check(f"{prefix}SetTime", set_time(comp, ctypes.c_double(tt)))
            xview[:] = x
            self._check(f"{prefix}SetContinuousStates", set_states(comp, xbuf, nx))
            self._check(f"{prefix}GetDerivatives", get_derivatives(comp, dxbuf, nx))
            return dxview.copy()

        # an integration is recorded as the step of the macro step it makes
        integration = guard.call(self, "fmi3DoStep" if self.fmi3 else "fmi2DoStep", t, step_index)
        integration.__enter__()  # left in the finally below
        try:
            x = self._x
            if self.nx:
                # the first step chosen from the start each time: a repeated integration repeats bit for bit
                solver = DOP853(rhs, t, x, t + H, rtol=self.tolerance, atol=self._atol)
                while solver.status == "running":
                    message = solver.step()
                    if solver.status == "failed":
                        raise UnitStepError(
                            f"unit {self.label}: the integrator failed in macro step {step_index} at t = "
                            f"{solver.t:.12g} s ({message}){self.said()}"
                        )
                    self.integrator_steps += 1
                    if solver.status == "running" and self._completed:
                        self._integrator_step(solver.t, solver.y, inputs_at, step_index)
                x = solver.y.copy()
                if not np.all(np.isfinite(x)):
                    raise UnitStepError(
                        f"unit {self.label}: its continuous states are not finite at the end of macro step "
                        f"{step_index} (t = {t + H:.12g} s){self.said()}"
                    )
            inputs_at(t + H)  # the input at u(1): the outputs read now are those at t + H
            self._x = x
            self._set_state(t + H, x)
            if self._completed:
                self._completed_step(t + H, step_index)
        except Exception as exc:
            if isinstance(exc, (UnitStepError, FmuError)):
                raise
            status = getattr(exc, "status", None)
            self.failed = status if status in (3, 4) else 0
            raise UnitStepError(
                f"unit {self.label} refused macro step {step_index} at t = {t:.12g} s ({exc}){self.said()}"
            ) from None
        finally:
            integration.__exit__(None, None, None)
        self.t = t + H

    def _driver(self, key, coefficients, t, H):
        """The function of time that sets the input(s) ``key`` to the coupling polynomial over ``[t, t + H]``
        (Horner's rule in ``tau``, in floats, in the unit's own units; ``key`` None: nothing to set).  A constant
        input is set once."""
        if key is None:
            return lambda tt: None
        c = (np.asarray(coefficients, dtype=float).reshape(len(coefficients), -1) / self.factors[key]).tolist()
        write = self._set_values
        if len(c) == 1:
            write(key, c[0])
            return lambda tt: None
        rows = c[::-1]
        if len(c[0]) == 1:  # one component: no inner lists
            terms = [row[0] for row in rows]

            def inputs_at(tt):
                tau = (tt - t) / H
                u = 0.0
                for cm in terms:
                    u = u * tau + cm
                write(key, [u])

            return inputs_at

        def inputs_at(tt):
            tau = (tt - t) / H
            u = [0.0] * len(rows[0])
            for row in rows:
                u = [a * tau + cm for a, cm in zip(u, row)]
            write(key, u)

        return inputs_at

    def _integrator_step(self, tt, x, inputs_at, step_index):
        """An accepted integrator step inside the macro step: the unit at it, told so."""
        inputs_at(tt)
        self._set_state(tt, x)
        self._completed_step(tt, step_index)

    def _completed_step(self, tt, step_index):
        event, terminate = self.fmu.completedIntegratorStep(True)  # no rollback to before it: states are ours
        if terminate:
            raise UnitStepError(f"unit {self.label} asked to terminate the simulation at t = {tt:.12g} s")
        if event:
            raise UnitStepError(
                f"unit {self.label} asked for a step event at t = {tt:.12g} s (macro step {step_index}); icosim "
                "integrates a model exchange unit without events: use interface co-simulation"
            )
