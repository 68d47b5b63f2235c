"""Stability of chains against the number of units: the spectral radius over the macro step and the largest
stable macro step, per unit kind, decomposition pattern, method, ``k`` and scheme.

The spectral radius ``rho`` of a whole chain (``docs/chains.md``, section 6) is computed in float64 with its
error estimate over a geometric scan of ``H`` (one batched call per configuration), every point as it is alone:
the estimate's disturbances are the same for every point of a batch, so no verdict depends on the other step
sizes computed with it.  A step size is **stable** where ``rho + error < 1``: a point float64 cannot decide
counts as not stable.  The largest stable ``H`` is the upper edge of the first stable band at or above the
scan's first point, bisected to the configured resolution (:func:`icosim.step_limit.stability_limit`: the
matrices of the next two halvings' step sizes in one batched macro step, the eigenvalues only of those it checks),
so ``rho < 1`` holds at ``H_max`` and not at ``H_unstable``, its neighbour above.

For two units of single masses the chain is the paper's two-mass model: the dataset holds that model's ``rho``
computed from its own parameters (:class:`~icosim.problems.linear.model.PhysicalModel`), the comparison the
``chain_two_unit`` check reads.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np

from ...engine.spectral.radius import Float64Radius, spectral_radius_float64
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.linear.chain import ChainFamily
from ...problems.linear.model import PhysicalModel
from ...problems.linear.spectral import spectral_radius_float64 as paper_rho
from ...step_limit import stability_limit
from .config import build_chain, method_of, pattern_decompositions, refusal, scheme_name

__all__ = ["scan_steps", "rho_over_H", "largest_stable_H", "two_mass_rho", "stability_data", "NOT_SERVED"]

#: ``status`` of a chain the model cannot build (a kinematically driven single mass in two joints).
NOT_SERVED = "not served"


def scan_steps(scan: dict) -> np.ndarray:
    """The scan's step sizes (s): ``n`` geometric points from ``min`` to ``max``."""
    return np.geomspace(float(scan["min"]), float(scan["max"]), int(scan["n"]))


def rho_over_H(chain, method, k: int, scheme: str):
    """``(rho, error)`` of the chain at each of its ``H`` (an array), each point's as alone (``pointwise``: the
    same in any batch)."""
    rho, err = spectral_radius_float64(ChainFamily(chain, k), method, scheme=scheme, pointwise=True)
    return np.asarray(rho, dtype=float), np.asarray(err, dtype=float)


def largest_stable_H(chain, method, k: int, scheme: str, scan, resolution: float, *, ahead: int = 2):
    """The :class:`~icosim.step_limit.Limit` of ``rho + error < 1`` over ``H``, and ``(rho, error)`` over the
    scan.  The scan's points are computed in one batch; the bisection forms the matrices of its next ``ahead``
    halvings' step sizes in one batched macro step and the eigenvalues only of those it checks
    (:func:`~icosim.step_limit.stability_limit`'s ``batch``; ``ahead=1``: one point at a time, the same
    result)."""
    scan = np.asarray(scan, dtype=float)
    rho, err = rho_over_H(chain.with_H(scan), method, k, scheme)
    known = {float(H): (float(r), float(e)) for H, r, e in zip(scan, rho, err)}

    def batch(Hs):
        todo = [H for H in Hs if H not in known]
        radius = None
        if todo:  # the matrices now, a point's eigenvalues when the bisection checks it
            family = ChainFamily(chain.with_H(np.array(todo)), k)
            radius = Float64Radius(family, method, scheme=scheme, pointwise=True)
        return _Verdicts(Hs, known, todo, radius)

    return stability_limit(None, scan, resolution=resolution, batch=batch, ahead=ahead), rho, err


class _Verdicts(Sequence):
    """``rho + error < 1`` at the step sizes ``Hs``, a point's ``(rho, error)`` computed when its verdict is read
    (``radius`` over the step sizes ``todo``, the others ``known``)."""

    def __init__(self, Hs, known, todo, radius):
        self.Hs, self.known, self.todo, self.radius = list(Hs), known, list(todo), radius

    def __len__(self):
        return len(self.Hs)

    def __getitem__(self, i):
        H = self.Hs[i]
        if H not in self.known:
            r, e = self.radius(np.arange(len(self.todo)) == self.todo.index(H))
            self.known[H] = (float(r[0]), float(e[0]))
        rho, err = self.known[H]
        return bool(rho + err < 1), {"rho": rho, "error": err}


def two_mass_rho(kind: list, decomposition: str, method, k: int, scheme: str, H) -> np.ndarray:
    """The paper's two-mass model with the first two single masses of ``kind``: its ``rho`` over ``H``."""
    (a, b) = kind[0], kind[1 % len(kind)]
    model = PhysicalModel(
        m1=a["masses"][0],
        m2=b["masses"][0],
        c1=a.get("ground_stiffness", [0.0])[0],
        c2=b.get("ground_stiffness", [0.0])[0],
        d1=a.get("ground_damping", [0.0])[0],
        d2=b.get("ground_damping", [0.0])[0],
        H=np.asarray(H, dtype=float),
    )
    return np.asarray(paper_rho(model.coefficients(), method, decomposition, k, scheme=scheme)[0], dtype=float)


def _rho_at(limit, H) -> float:
    for h, _, info in limit.evaluations:
        if h == H:
            return info["rho"]
    return math.nan


def stability_data(cfg: dict, *, command: str = "", log=None) -> DatasetDict:
    """The stability dataset of ``cfg`` (``config/chains.yaml``'s ``chains``)."""
    st, units, methods = cfg["stability"], cfg["units"], cfg["methods"]
    scan = scan_steps(st["scan"])
    dims = {
        "unit": list(st["units"]),
        "pattern": list(st["patterns"]),
        "n_units": list(st["n_units"]),
        "method": list(st["methods"]),
        "k": list(st["k"]),
        "scheme": list(st["schemes"]),
    }
    shape = tuple(len(v) for v in dims.values())
    rho = np.full(shape + (scan.size,), np.nan)
    rho_err = np.full_like(rho, np.nan)
    rho_pair = np.full((shape[0], shape[1], shape[3], shape[4], shape[5], scan.size), np.nan)
    out = {name: np.full(shape, np.nan) for name in ("H_max", "H_unstable", "rho_at_H_max", "rho_at_H_unstable")}
    status = np.full(shape, NOT_SERVED, dtype=object)
    for idx in itertools.product(*(range(n) for n in shape)):
        unit, pattern, n, mname, k, kind = (dims[d][i] for d, i in zip(dims, idx))
        if refusal(units[unit], pattern, n) is not None:
            continue  # recorded as not served
        method, scheme = method_of(methods, mname), scheme_name(kind, n)
        chain = build_chain(units[unit], pattern, n, 1.0)
        lim, rho[idx], rho_err[idx] = largest_stable_H(chain, method, k, scheme, scan, st["resolution"])
        out["H_max"][idx], out["H_unstable"][idx], status[idx] = lim.H_max, lim.H_unstable, lim.status
        out["rho_at_H_max"][idx], out["rho_at_H_unstable"][idx] = _rho_at(lim, lim.H_max), _rho_at(lim, lim.H_unstable)
        if n == 2 and len(units[unit][0]["masses"]) == 1:
            dec = pattern_decompositions(pattern, 2)[0]
            rho_pair[idx[:2] + idx[3:]] = two_mass_rho(units[unit], dec, method, k, scheme, scan)
        if log:
            log(f"{unit} {pattern} N={n} {mname} k={k} {kind}: H_max {lim.H_max:.4g} s ({lim.status})")
    names = list(dims)
    coords = {d: (d, np.array(v)) for d, v in dims.items()}
    coords["H"] = ("H", scan, {"units": "s", "long_name": "macro step size of the scan"})
    coords["n_units"] = ("n_units", np.array(dims["n_units"]), {"units": "1", "long_name": "number of units N"})
    coords["k"] = ("k", np.array(dims["k"]), {"units": "1", "long_name": "polynomial degree of the approximation"})
    coords["scheme"] = (
        "scheme",
        np.array(dims["scheme"]),
        {"long_name": "coupling scheme: Jacobi, Gauss-Seidel in the order 1 -> N (forward) or N -> 1 (reverse)"},
    )
    bracket = "of the first stable band at or above the scan's first H"
    ds = DatasetDict(
        {
            "rho": (names + ["H"], rho, {"units": "1", "long_name": "spectral radius of the chain's recurrence"}),
            "rho_error": (names + ["H"], rho_err, {"units": "1", "long_name": "float64 error estimate of rho"}),
            "rho_two_mass": (
                ["unit", "pattern", "method", "k", "scheme", "H"],
                rho_pair,
                {
                    "units": "1",
                    "long_name": "spectral radius of the paper's two-mass model with the kind's first two masses",
                    "comment": "only for kinds of single masses; NaN otherwise",
                },
            ),
            "H_max": (names, out["H_max"], {"units": "s", "long_name": f"largest stable macro step {bracket}"}),
            "H_unstable": (
                names,
                out["H_unstable"],
                {"units": "s", "long_name": "the unstable macro step just above H_max (bisection bracket)"},
            ),
            "rho_at_H_max": (names, out["rho_at_H_max"], {"units": "1", "long_name": "rho at H_max"}),
            "rho_at_H_unstable": (names, out["rho_at_H_unstable"], {"units": "1", "long_name": "rho at H_unstable"}),
            "status": (
                names,
                status.astype(str),
                {
                    "long_name": "outcome of the search",
                    "flag_values": "bisected, stable up to the cap, no stable step size, not served",
                },  # fmt: skip
            ),
        },
        coords=coords,
    )
    ds.attrs.update(provenance_attrs(cfg, title="Chains: stability against the number of units", command=command))
    ds.attrs.update(
        part="chains",
        dataset="stability",
        stable_if="rho + rho_error < 1",
        resolution=float(st["resolution"]),
    )
    return ds
