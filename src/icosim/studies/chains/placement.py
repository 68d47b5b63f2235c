"""Where a heavy or stiff unit sits in a chain: the spectral radius and the largest stable macro step with one
unit changed at the first, middle or last place, against the chain with no unit changed.

A **variant** scales some of a unit's parameters (``masses``, ``ground_stiffness``, ``ground_damping``) by
factors; the changed unit is the chain's unit at that place with its parameters scaled.  The search is that of
:mod:`icosim.studies.chains.stability`.
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np

from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.linear.chain import Chain
from .config import build_chain, method_of, scheme_name
from .stability import largest_stable_H, scan_steps

__all__ = ["POSITIONS", "position_index", "changed_chain", "placement_data"]

#: Where the changed unit sits; ``none``: the chain with no unit changed.
POSITIONS = ("none", "first", "middle", "last")


def position_index(position: str, n_units: int) -> int | None:
    """The changed unit's index (0-based), or None for ``none``; the middle of an even chain is its lower
    middle unit."""
    return {"none": None, "first": 0, "middle": (n_units - 1) // 2, "last": n_units - 1}[position]


def changed_chain(chain: Chain, factors: dict, position: str) -> Chain:
    """``chain`` with the unit at ``position`` scaled by ``factors`` (parameter -> factor)."""
    i = position_index(position, chain.n_segments)
    if i is None:
        return chain
    seg = chain.segments_[i]
    scaled = replace(seg, **{key: tuple(f * v for v in getattr(seg, key)) for key, f in factors.items()})
    segs = chain.segments_[:i] + (scaled,) + chain.segments_[i + 1 :]
    return replace(chain, segments_=segs)


def placement_data(cfg: dict, *, command: str = "", log=None) -> DatasetDict:
    """The placement dataset of ``cfg`` (``config/chains.yaml``'s ``chains``)."""
    pl, methods = cfg["placement"], cfg["methods"]
    scan, n = scan_steps(cfg["stability"]["scan"]), int(pl["n_units"])
    base = build_chain(cfg["units"][pl["unit"]], pl["pattern"], n, 1.0)
    dims = {
        "variant": list(pl["variants"]),
        "position": list(POSITIONS),
        "method": list(pl["methods"]),
        "k": list(pl["k"]),
        "scheme": list(pl["schemes"]),
    }
    shape = tuple(len(v) for v in dims.values())
    rho = np.full(shape + (scan.size,), np.nan)
    H_max, H_unstable = np.full(shape, np.nan), np.full(shape, np.nan)
    status = np.full(shape, "", dtype=object)
    searched = {}  # the chain with no unit changed is the same for every variant: searched once
    for idx in itertools.product(*(range(s) for s in shape)):
        variant, position, mname, k, kind = (dims[d][i] for d, i in zip(dims, idx))
        key = (None if position == "none" else variant, position, mname, k, kind)
        if key not in searched:
            chain = changed_chain(base, pl["variants"][variant], position)
            searched[key] = largest_stable_H(
                chain, method_of(methods, mname), k, scheme_name(kind, n), scan, cfg["stability"]["resolution"]
            )
        lim, rho[idx], _ = searched[key]
        H_max[idx], H_unstable[idx], status[idx] = lim.H_max, lim.H_unstable, lim.status
        if log:
            log(f"{variant} at {position}, {mname} k={k} {kind}: H_max {lim.H_max:.4g} s ({lim.status})")
    names = list(dims)
    coords = {d: (d, np.array(v)) for d, v in dims.items()}
    coords["H"] = ("H", scan, {"units": "s", "long_name": "macro step size of the scan"})
    coords["position"] = (
        "position",
        np.array(POSITIONS),
        {"long_name": "place of the changed unit in the chain (none: no unit changed)"},
    )
    ds = DatasetDict(
        {
            "rho": (names + ["H"], rho, {"units": "1", "long_name": "spectral radius of the chain's recurrence"}),
            "H_max": (names, H_max, {"units": "s", "long_name": "largest stable macro step"}),
            "H_unstable": (names, H_unstable, {"units": "s", "long_name": "the unstable macro step just above H_max"}),
            "status": (names, status.astype(str), {"long_name": "outcome of the search"}),
        },
        coords=coords,
    )
    ds.attrs.update(provenance_attrs(cfg, title="Chains: where a heavy or stiff unit sits", command=command))
    variants = "; ".join(
        f"{v}: " + ", ".join(f"{key} x {f:g}" for key, f in factors.items()) for v, factors in pl["variants"].items()
    )
    ds.attrs.update(
        part="chains",
        dataset="placement",
        n_units=n,
        unit=pl["unit"],
        pattern=pl["pattern"],
        variants=variants,
        resolution=float(cfg["stability"]["resolution"]),
        middle_unit=(position_index("middle", n) or 0) + 1,
        stable_if="rho + rho_error < 1",
    )
    return ds
