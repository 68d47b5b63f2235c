"""A scene's ``initial_coupling`` against the coupling variables its units need at ``t_start``."""

from __future__ import annotations

import numpy as np

__all__ = ["given_coupling_warning"]


def given_coupling_warning(path, given, computed, rtol: float = 1e-6) -> str:
    """A warning where the scene's ``initial_coupling`` departs from the coupling variables the units need at
    ``t_start`` (beyond ``rtol`` of the larger of 1 and their size): the history then starts off the solution, an
    error of the size of the departure that the following steps carry (first order in H, whatever the method's
    order); ``""`` where they agree."""
    scale = max(1.0, float(np.max(np.abs(computed))), float(np.max(np.abs(given))))
    if float(np.max(np.abs(given - computed))) <= rtol * scale:
        return ""
    fmt = lambda v: "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
    return (
        f"{path}: initial_coupling: {fmt(given)} differs from the coupling variables the units need at "
        f"t_start, {fmt(computed)} (computed from the units); a start off the units costs the run its order "
        "(first-order accurate in H): leave initial_coupling out to start from the computed values"
    )
