"""One coupling method for the points of a batch whose constraint levels differ per point.

The ball macro step of one point costs mostly Python calls, not arithmetic, so the step sizes of a
convergence curve have their ball matrices formed in one batched step (a leading axis of object
arrays).  A dimensional method (Baumgarte's ``mu``) has other engine levels ``beta_bar = beta / H``,
``gamma_bar = gamma / H^2`` at every step size: :func:`pointwise_method` stands for all of them, each
level that differs a tuple of one level per point, which the engine multiplies into each point's rows
as that point's level does alone (:class:`icosim.engine.methods.CouplingMethod`): the same ball
products, hence the same balls.  Points whose levels are 0 or 1 at different levels form other
products and go to different batches (:func:`structure`).

>>> from icosim.studies.convergence.experiment import Setup, dimensional_method
>>> from icosim.engine.backends import Ball
>>> from icosim.engine.spectral.matrix import amplification_matrix
>>> H = (1e-3, 4e-3)
>>> methods = [dimensional_method("baumgarte", h, index=1, mu=5e-3) for h in H]
>>> be = Ball(256)
>>> with be.context():
...     points = [Setup().model(h).coefficients().map(be.const) for h in H]
...     batch = amplification_matrix(stacked(points), pointwise_method(methods), "ff", 1, backend=be)
...     alone = [amplification_matrix(p, m, "ff", 1, backend=be) for p, m in zip(points, methods)]
>>> all(a.mid() == b.mid() and a.rad() == b.rad() for M, A in zip(batch, alone) for a, b in zip(M.flat, A.flat))
True
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["pointwise_method", "stacked", "structure"]


def structure(method):
    """What must agree for methods to share one batched step: all but the values of their levels (whether
    each is 0 or 1 included, which decides which products the rule forms)."""
    solves = tuple((weight, tuple((level == 0, level == 1) for level in levels)) for weight, levels in method.solves)
    return (type(method), method.name, method.projection, method.requires_constraint, method.refusal, solves)


def pointwise_method(methods):
    """The method standing for ``methods`` (one per point, the same :func:`structure`): their first, with
    each level that differs between the points as the tuple of the points' levels."""
    first = methods[0]
    solves = []
    for s, (weight, _) in enumerate(first.solves):
        columns = zip(*(m.solves[s][1] for m in methods))
        solves.append((weight, tuple(c[0] if len(set(c)) == 1 else tuple(c) for c in columns)))
    return dataclasses.replace(first, solves=tuple(solves))


def stacked(points):
    """Coefficients of single points (balls) as one set of coefficients with a leading axis of the points."""
    columns = []
    for f in dataclasses.fields(points[0]):
        column = np.empty(len(points), dtype=object)
        column[:] = [getattr(c, f.name) for c in points]
        columns.append(column)
    return type(points[0])(*columns)
