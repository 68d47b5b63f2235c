"""The projection step (Eq. 30) on any coupling graph: positions and velocities of the ports moved onto the
joints' constraints, mass-weighted.

The corrector leaves the joined ports apart by the drift of the constraint.  The projection moves the
ports' coordinates ``x`` (positions, and velocities alike) by the smallest mass-weighted change that closes
every joint: minimise ``sum_p m_p |dx_p|^2`` subject to ``G (x + dx) = 0``, ``G`` the joints' rows (``+1`` at
the first port, ``-1`` at the second).  So ``dx = -W G^T (G W G^T)^-1 G x`` with ``W = diag(1/m_p)``; for two
ports both end at the mass-weighted mean ``(m_1 x_1 + m_2 x_2) / (m_1 + m_2)``, the paper's Eq. (30).  The
problem owns its coordinates; this is the linear algebra, in any of the engine's arithmetics.

>>> import numpy as np
>>> from icosim.engine.graph import CouplingGraph
>>> x = np.array([[1.0], [4.0]])  # two ports, one coordinate
>>> mass_weighted_projection(CouplingGraph.pair("ff"), np.array([1.0, 2.0]), x).ravel().tolist()
[3.0, 3.0]
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .graph import CouplingGraph
from .methods.base import solve_small

__all__ = ["mass_weighted_projection"]


def mass_weighted_projection(graph: CouplingGraph, masses: Any, x: Any) -> Any:
    """``x`` (``(..., n_ports, d)``, every port of ``graph`` in its numbering, any coordinates the joints
    constrain to be equal) projected onto the joints' constraints with the ports' ``masses`` (``(...,
    n_ports)``, broadcast)."""
    offsets = graph.port_offsets
    pairs = [(offsets[jt.first] + jt.ports[0], offsets[jt.second] + jt.ports[1]) for jt in graph.joints]
    w = 1 / masses
    # G W G^T: the joints that share a port are coupled through its inverse mass
    rows = []
    for a, b in pairs:
        row = []
        for c, d in pairs:
            entry = None
            for p, sign in ((c, 1), (d, -1)):
                s = (1 if p == a else -1 if p == b else 0) * sign
                if s:
                    term = w[..., p] if s > 0 else -w[..., p]
                    entry = term if entry is None else entry + term
            row.append(entry if entry is not None else 0 * w[..., 0])
        rows.append(np.stack(np.broadcast_arrays(*row), axis=-1))
    A = np.stack(np.broadcast_arrays(*rows), axis=-2)  # (..., n, n)
    r = np.stack([x[..., a, :] - x[..., b, :] for a, b in pairs], axis=-2)  # (..., n, d)
    lam = np.stack([solve_small(A, r[..., :, c]) for c in range(r.shape[-1])], axis=-1)  # (..., n, d)
    out = np.array(np.broadcast_to(x, np.broadcast_shapes(x.shape, lam.shape[:-2] + x.shape[-2:])), copy=True)
    for j, (a, b) in enumerate(pairs):
        out[..., a, :] = out[..., a, :] - w[..., a, None] * lam[..., j, :]
        out[..., b, :] = out[..., b, :] + w[..., b, None] * lam[..., j, :]
    return out
