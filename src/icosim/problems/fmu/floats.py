"""The FMU problem's arithmetic of one point in Python floats (:mod:`icosim.problems.fmu.problem`): sums and
products in the order numpy would make them, so the same numbers, without numpy's overhead on a few values."""

from __future__ import annotations

__all__ = ["projected", "summed", "gathered"]


def projected(clusters, masses, rows):
    """:func:`icosim.engine.projection.mass_weighted_projection` of one point in floats (rows of floats, a mass
    per row): the same products, sums and quotient in the same order, so the same numbers."""
    out = list(rows)
    for cluster in clusters:
        weighted = [masses[cluster[0]] * v for v in rows[cluster[0]]]
        total = masses[cluster[0]]
        for b in cluster[1:]:
            m = masses[b]
            weighted = [w + m * v for w, v in zip(weighted, rows[b])]
            total = total + m
        mean = [w / total for w in weighted]
        for b in cluster:
            out[b] = mean
    return out


def summed(rows, negated=False):
    """The rows' sum (floats, added in order), negated if asked: a polynomial's value at the step's end."""
    if len(rows[0]) == 1:
        total = rows[0][0]
        for row in rows[1:]:
            total = total + row[0]
        return [-total if negated else total]
    out = rows[0]
    for row in rows[1:]:
        out = [a + b for a, b in zip(out, row)]
    return [-v for v in out] if negated else out


def gathered(row, terms):
    """A unit's inputs from one row of coupling variables: per input the sum of its ``(column, sign)`` terms,
    as :meth:`icosim.engine.graph.CouplingGraph.inputs` forms it (signs +-1: exact products)."""
    out = []
    for term in terms:
        (c, sign), *rest = term
        total = row[c] if sign == 1 else -row[c]
        for c, sign in rest:
            total = total + row[c] * sign
        out.append(total)
    return out
