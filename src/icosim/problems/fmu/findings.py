"""A check's finding, and the relative difference the checks compare with."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Finding", "relative"]


@dataclass(frozen=True)
class Finding:
    """One check of one unit: ``verdict`` is ``pass``, ``refused`` or ``note``."""

    check: str
    verdict: str
    detail: str
    fix: str = ""
    key: str = ""  # the scene key a refusal is about, where it is one


def relative(a, b) -> np.ndarray:
    """``|a - b| / max(|a|, |b|)`` elementwise (0 where both are 0, inf where either is not finite)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    size = np.maximum(np.abs(a), np.abs(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.where(a == b, 0.0, np.abs(a - b) / size)
    return np.where(np.isfinite(a) & np.isfinite(b), d, np.inf)
