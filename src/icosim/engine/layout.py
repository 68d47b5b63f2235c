"""Memory layout of batched float64 arrays: the batch axes (a parameter grid) vary fastest.

The engine's arrays carry a batch on their *leading* axes (a whole parameter grid, and the unit
vectors an amplification matrix is built from) and the small state, history and matrix axes last.
Laid out in NumPy's default (C) order, the innermost loop of every elementwise operation runs over
a trailing axis of length 2 to 10, and the loop overhead costs more than the arithmetic.  Laid out
with the batch axes fastest (the Fortran order of the whole array), the same operations run their
inner loops over the grid.

The values are the same bit for bit: an elementwise operation computes each element alone, in
whatever order memory is walked.  Only what goes to BLAS sees the layout (``@``, where NumPy hands
each stacked product to ``dgemm``); those operands are kept C-contiguous as before
(:meth:`icosim.problems.linear.subsystems.LinearSubsystem.node_matrices`).  Elementwise results follow the
layout of their operands (NumPy's ``K`` order), so it is set where arrays are made: the subsystems'
exponential blocks and the coefficients (:func:`batched`), and the stacked and concatenated arrays
(:func:`stack`, :func:`concatenate`, which are :func:`numpy.stack` and :func:`numpy.concatenate` with
that layout).

Small arrays (one point: the pendulum's macro step, the convergence runs) and object arrays
(mpmath, balls) are made exactly as NumPy makes them.

>>> a = np.zeros((101, 101, 3))
>>> stack([a, a], axis=-1).strides[:2], np.stack([a, a], axis=-1).strides[:2]
((8, 808), (4848, 48))
>>> stack([np.zeros(2), np.ones(2)]).flags.c_contiguous  # small: as NumPy makes it
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = ["stack", "concatenate", "batched", "BATCH_SIZE"]

#: Arrays with at least this many elements (and three axes) are laid out with the batch axes fastest.
BATCH_SIZE = 4096


def _is_batch(a: np.ndarray) -> bool:
    return a.dtype.kind == "f" and a.ndim >= 3 and a.size >= BATCH_SIZE


def batched(a: Any) -> Any:
    """``a`` with the batch (leading) axes fastest if it is a large float array, else ``a`` itself."""
    return np.asfortranarray(a) if isinstance(a, np.ndarray) and _is_batch(a) and not a.flags.f_contiguous else a


def stack(arrays: Iterable[Any], axis: int = 0) -> np.ndarray:
    """:func:`numpy.stack` (the same values), the result laid out with the batch axes fastest if large."""
    arrays = [np.asarray(a) for a in arrays]
    first = arrays[0]
    if not all(a.shape == first.shape for a in arrays) or not all(a.dtype.kind == "f" for a in arrays):
        return np.stack(arrays, axis=axis)
    ax = axis + first.ndim + 1 if axis < 0 else axis
    shape = first.shape[:ax] + (len(arrays),) + first.shape[ax:]
    if not (len(shape) >= 3 and first.size * len(arrays) >= BATCH_SIZE):
        return np.stack(arrays, axis=axis)
    out = np.empty(shape, dtype=np.result_type(*arrays), order="F")
    return np.stack(arrays, axis=axis, out=out)


def concatenate(arrays: Iterable[Any], axis: int = 0) -> np.ndarray:
    """:func:`numpy.concatenate` (the same values), the result laid out with the batch axes fastest if large."""
    arrays = [np.asarray(a) for a in arrays]
    first = arrays[0]
    nd = first.ndim
    if nd < 3 or not all(a.ndim == nd and a.dtype.kind == "f" for a in arrays):
        return np.concatenate(arrays, axis=axis)
    ax = axis + nd if axis < 0 else axis
    if not all(a.shape[:ax] + a.shape[ax + 1 :] == first.shape[:ax] + first.shape[ax + 1 :] for a in arrays):
        return np.concatenate(arrays, axis=axis)  # NumPy raises its own error
    shape = first.shape[:ax] + (sum(a.shape[ax] for a in arrays),) + first.shape[ax + 1 :]
    if math.prod(shape) < BATCH_SIZE:
        return np.concatenate(arrays, axis=axis)
    out = np.empty(shape, dtype=np.result_type(*arrays), order="F")
    return np.concatenate(arrays, axis=axis, out=out)
