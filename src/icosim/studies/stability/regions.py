"""The grid points of a stability panel that a claim reads: a region of the plane, and the verdict masks.

A claim's ``region`` bounds ``lr1`` and ``li1`` and may leave out the
undamped axis ``lr1 = 0`` and the origin (free masses); the verdicts
(:data:`icosim.engine.spectral.policy.VERDICTS`) split the points into stable,
unstable and the rest (marginal or undecided).  Shared by the share checks
(:mod:`icosim.studies.stability.checks`) and the point-by-point one
(:mod:`icosim.studies.stability.pointwise`).
"""

from __future__ import annotations

import numpy as np

from ...engine.spectral.policy import VERDICTS
from ...errors import ParameterError

__all__ = ["REGION_KEYS", "region_mask", "verdict_masks", "validate_region"]

#: Keys of a claim's ``region``: bounds on ``lr1``/``li1``, and the degenerate points left out.
REGION_KEYS = ("lr1", "li1", "exclude_undamped", "exclude_origin")


def region_mask(ds, region):
    """Boolean ``(lr1, li1)`` mask of the points of ``ds`` inside ``region`` (None: every point)."""
    lr1 = np.asarray(ds["lr1"])[:, None]
    li1 = np.asarray(ds["li1"])[None, :]
    mask = np.ones((lr1.size, li1.size), dtype=bool)
    region = region or {}
    unknown = sorted(set(region) - set(REGION_KEYS))
    if unknown:
        raise ParameterError(f"region: unknown key(s) {unknown}; allowed: {', '.join(REGION_KEYS)}")
    if "lr1" in region:
        lo, hi = region["lr1"]
        mask &= (lr1 >= lo) & (lr1 <= hi)
    if "li1" in region:
        lo, hi = region["li1"]
        mask &= (li1 >= lo) & (li1 <= hi)
    if region.get("exclude_undamped"):
        # lr1 = 0: both subsystems undamped, the model itself only marginally stable
        mask &= np.broadcast_to(lr1 < 0, mask.shape)
    if region.get("exclude_origin"):
        # lr1 = li1 = 0: both subsystems are free masses (lambda_2 = 0 too); every scheme reproduces the rigid motion
        # x0 + v t, so 1 is an eigenvalue and rho >= 1 there: marginal or unstable, never provably stable
        mask &= (lr1 != 0) | (li1 != 0)
    return mask


def verdict_masks(ds):
    """``(stable, unstable)`` masks of a panel; the rest is marginal or undecided."""
    if "verdict" not in ds:  # a panel without verdicts (written before certification): every point decided
        stable = np.asarray(ds["stable"]).astype(bool)
        return stable, ~stable
    v = np.asarray(ds["verdict"])
    return v == VERDICTS.index("stable"), v == VERDICTS.index("unstable")  # the datasets' flag values


def validate_region(label: str, params: dict):
    """A check's ``region`` parameter, when claims are read (errors name the claim and the key)."""
    region = params.get("region")
    if region is None:
        return
    if not isinstance(region, dict):
        raise ParameterError(f"{label}: check.region must be a mapping of attribute -> value")
    unknown = sorted(set(region) - set(REGION_KEYS))
    if unknown:
        raise ParameterError(f"{label}: check.region has unknown key(s) {unknown}; allowed: {', '.join(REGION_KEYS)}")
