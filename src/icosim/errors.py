"""The error types of icosim that a user catches, in one place (this module imports nothing of icosim).

===============================  ==============================================================
error                            raised when
===============================  ==============================================================
:class:`ParameterError`          a model, method, scheme or study parameter is invalid; the
                                 message names the parameter (a :class:`ValueError`)
:class:`NotFiniteError`          a derived quantity (a subsystem coefficient) is not a finite
                                 float64 (a :class:`ParameterError` and an :class:`OverflowError`)
:class:`PrecisionCapError`       the precision a point needs exceeds a cap: it is undecided
:class:`PointTimeout`            one point took longer than its time budget: it is undecided
:class:`StepFailure`             a macro step could not be computed (a failed run, not a
                                 diverged one)
:class:`CorruptDatasetError`     a dataset's SHA-256 no longer matches the one recorded when it
                                 was written
===============================  ==============================================================

Failures of one integrator (:class:`icosim.problems.pendulum.integrator.systems.IntegrationError`, the
pendulum's projection) are :class:`StepFailure` subclasses kept beside the code that raises them.
"""

from __future__ import annotations

__all__ = [
    "ParameterError",
    "NotFiniteError",
    "PrecisionCapError",
    "PointTimeout",
    "StepFailure",
    "CorruptDatasetError",
]


class ParameterError(ValueError):
    """Invalid model or method parameter; the message names the parameter."""


class NotFiniteError(ParameterError, OverflowError):
    """A derived quantity (a subsystem coefficient) that is not a finite float64."""


class PrecisionCapError(ArithmeticError):
    """The precision a point needs exceeds a cap: it is undecided (the message says why)."""


class PointTimeout(ArithmeticError):
    """One point took longer than its time budget: it is undecided (reason ``timeout``)."""


class StepFailure(RuntimeError):
    """A macro step could not be computed (e.g. a subsystem integration failed).

    :func:`icosim.engine.macrostep.simulate` records it as a *failed* run, distinct from a diverged one:
    a failure says nothing about the stability of the coupling.
    """


class CorruptDatasetError(OSError):
    """A dataset whose SHA-256 no longer matches the one recorded when it was written."""
