"""The error of an FMU scene: a unit, a variable, a key or a step that cannot be used, named in the message."""

from __future__ import annotations

from ...errors import ParameterError, StepFailure

__all__ = ["FmuError", "SceneError", "UnitStepError"]


class SceneError(ParameterError):
    """A scene file that cannot be run: the message names the file and the key (and the allowed values)."""


class FmuError(SceneError):
    """A unit that cannot be used: missing or corrupt, of the wrong kind, lacking a capability or a variable."""


class UnitStepError(StepFailure):
    """A unit refused a step (``fmi2Discard``/``fmi2Error``): the message names the unit, the step and the time."""
