"""The orders of input derivatives a Co-Simulation unit takes, checked before any step.

A unit that declares ``canInterpolateInputs`` takes its inputs over a macro step as their value and time
derivatives at its start (``fmi2SetRealInputDerivatives``, :meth:`icosim.problems.fmu.units.Unit.step`): every
order up to the degree of the coupling polynomial, ``k`` (``k + 1`` for a velocity drive, ``k + 2`` for a
position drive: :func:`icosim.problems.fmu.drives.drive_rows`).  FMI 2.0 declares no highest order of input
derivatives (``maxOutputDerivativeOrder`` is the outputs'), and a unit may refuse one: OpenModelica's units take
the first derivative and answer the second with ``fmi2Error``.  :func:`check_input_orders` hands the unit zeros
of every order it will be handed, once, right after it is opened, and refuses by name the first order it does not
take, with the ways round it (sub-steps, a lower ``k``, model exchange).  A zero derivative is a held input, what
the unit is handed before the run's first step (the checks' held steps) anyway.
"""

from __future__ import annotations

from .errors import FmuError

__all__ = ["check_input_orders", "input_order"]

#: The degree a drive input adds to the coupling polynomial's (``k``): the acceleration integrated once or twice.
_DRIVE_DEGREE = {"acceleration_input": 0, "velocity_input": 1, "position_input": 2}


def input_order(unit, k: int) -> tuple[str | None, int]:
    """The key under which ``unit`` is stepped by derivatives and the highest derivative order it is handed at
    extrapolation order ``k``; ``(None, 0)`` for a unit that is handed none (sub-steps, model exchange, no input)."""
    if not getattr(unit, "exact_inputs", False):
        return None, 0
    if unit.drive_keys:
        return "drive", int(k) + max(_DRIVE_DEGREE[key] for key in unit.drive_keys)
    key = next((key for key in ("force", "acceleration_input", "signal_input") if key in unit.elements), None)
    return key, (int(k) if key is not None else 0)


def check_input_orders(path, unit, k: int):
    """``unit``, after handing it zeros of each input derivative order it will be handed (:func:`input_order`);
    a unit that refuses one is closed and refused with an :class:`~icosim.problems.fmu.errors.FmuError` naming it,
    its capability attributes, the order it refused, ``coupling.k`` and ``coupling.inputs``, and the fixes."""
    key, order = input_order(unit, k)
    refs = unit.fmi.refs(key) if key is not None else []
    for m in range(1, order + 1):
        try:
            unit.fmi.set_input_derivatives(refs, [m] * len(refs), [0.0] * len(refs))
        except Exception as exc:
            status = getattr(exc, "status", None)
            unit.failed = status if status in (3, 4) else 0
            said = unit.said()
            unit.close()
            raise FmuError(_refusal(path, unit, k, key, m, order) + said) from None
    return unit


def _refusal(path, unit, k, key, refused, order) -> str:
    """The refusal of a unit that took the derivatives of orders below ``refused`` and not ``refused``."""
    cs, me = unit.md.coSimulation, unit.md.modelExchange
    extra = order - int(k)
    declared = f"canInterpolateInputs=true, maxOutputDerivativeOrder={getattr(cs, 'maxOutputDerivativeOrder', 0)}"
    names = [el.variable.name for el in unit.elements[key]]
    what = f"its input{'s' if len(names) > 1 else ''} {', '.join(names)}" + (
        f" (a drive: degree k + {extra})" if extra else ""
    )
    fixes = ["coupling.inputs: substeps (the polynomial sampled in sub-steps, no derivatives)"]
    if refused - 1 - extra >= 0:
        fixes.append(f"coupling.k: {refused - 1 - extra} or lower")
    if me is not None:
        fixes.append(f"subsystems.{unit.label}.interface: model-exchange (icosim integrates it)")
    takes = f"orders below {refused}" if refused > 1 else "none"
    return (
        f"{path}: subsystems.{unit.label}: {unit.path.name} ({declared}; FMI 2.0 declares no highest order of "
        f"input derivatives) refuses fmi2SetRealInputDerivatives of order {refused}, which coupling.k: {k} with "
        f"coupling.inputs derivatives (or auto, the default) hands {what} at every macro step (orders 1 to "
        f"{order}); it takes {takes}: use {'; or '.join(fixes)}"
    )
