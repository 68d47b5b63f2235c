"""The projection step (Eq. 30) on any coupling graph: positions and velocities moved onto the joints'
constraints, mass-weighted.

The corrector leaves the joined ports apart by the drift of the constraint.  The projection moves the
coordinates ``x`` of the bodies the ports belong to (positions, and velocities alike) by the smallest
mass-weighted change that closes every joint: minimise ``sum_b m_b |dx_b|^2`` subject to every joint's two
bodies being equal.  The joints split the bodies into clusters that must end equal (a chain of rigid joints
is one cluster); the minimiser moves each cluster to its mass-weighted mean ``sum m_b x_b / sum m_b`` --
for two bodies the paper's Eq. (30), ``(m_1 x_1 + m_2 x_2) / (m_1 + m_2)`` -- and leaves a body in no joint
where it is.  The problem says which body each port belongs to (a single-mass segment's two ports are one
body).

>>> import numpy as np
>>> from icosim.engine.graph import CouplingGraph
>>> clusters = joined_clusters(CouplingGraph.pair("ff"), [0, 1])
>>> mass_weighted_projection(clusters, np.array([1.0, 2.0]), np.array([[1.0], [4.0]])).ravel().tolist()
[3.0, 3.0]
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from . import layout
from .graph import CouplingGraph

__all__ = ["joined_clusters", "mass_weighted_projection"]


def joined_clusters(graph: CouplingGraph, body_of_port: Sequence[int]) -> tuple[tuple[int, ...], ...]:
    """The bodies the joints hold together, cluster by cluster (bodies in no joint are left out);
    ``body_of_port[g]`` is the body of port ``g`` in the graph's numbering of ports."""
    parent: dict[int, int] = {}

    def root(b: int) -> int:
        while parent.setdefault(b, b) != b:
            b = parent[b]
        return b

    offsets = graph.port_offsets
    for joint in graph.joints:
        a = body_of_port[offsets[joint.first] + joint.ports[0]]
        b = body_of_port[offsets[joint.second] + joint.ports[1]]
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    clusters: dict[int, list[int]] = {}
    for b in sorted(parent):
        clusters.setdefault(root(b), []).append(b)
    return tuple(tuple(c) for c in clusters.values())


def mass_weighted_projection(clusters: Sequence[Sequence[int]], masses: Any, x: Any) -> Any:
    """``x`` (``(..., n_bodies, d)``) with every cluster's bodies moved to their mass-weighted mean
    (``masses``: ``(..., n_bodies)``, broadcast); in the arithmetic of the arrays."""
    lead = x.shape[:-2] if x.shape[:-2] == masses.shape[:-1] else np.broadcast_shapes(x.shape[:-2], masses.shape[:-1])
    if x.shape[:-2] != lead:
        x = np.broadcast_to(x, lead + x.shape[-2:])
    rows = [x[..., b, :] for b in range(x.shape[-2])]  # every one, a cluster's mean too, of shape lead + (d,)
    for cluster in clusters:
        weighted: Any = None
        total: Any = None
        for b in cluster:
            m = masses[..., b, None]
            term = m * x[..., b, :]
            weighted = term if weighted is None else weighted + term
            total = m if total is None else total + m
        mean = weighted / total
        for b in cluster:
            rows[b] = mean
    return layout.stack(rows, axis=-2)
