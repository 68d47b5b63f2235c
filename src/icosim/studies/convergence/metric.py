"""The normalised root-mean-square error of Eq. (72).

Eq. (72), decision
------------------
The extracted formula is garbled: it shows two brackets, each closed by
``]^{1/2}``, one with the two position terms and one with the two velocity
terms, and only one opening bracket.  We read it as **one** bracket::

    eps_glo = sqrt( sum_j  sum_N (y_j(T_N) - y_j,N)^2 / sum_N (y_j(T_N) - y_j,mean)^2 ),
    y = (x1, x2, v1, v2),   y_j,mean = sum_N y_j(T_N) / N_total,

the sum over ``N = 1 ... N_total`` (``N_total`` macro steps; ``T_0`` carries no
error by construction and the mean is "sum over N divided by N_total").  This
is the normalised root-mean-square error the text describes ("mean of the
squared difference ... divided by the variance of the reference"), summed over
the four variables.  The other reading (separate square roots for positions and
velocities, added) differs by at most a factor ``sqrt(2)`` and cannot change an
order of convergence.  Both readings can be rebuilt from the datasets, which
also store the two partial sums ``nrmse_x`` (x1, x2) and ``nrmse_v`` (v1, v2):
``nrmse = sqrt(nrmse_x^2 + nrmse_v^2)``, the other reading is
``nrmse_x + nrmse_v``.  ``nrmse_lambda`` is the same measure for the constraint
force ``lambda_c`` (ff, fd; the corrected coupling variable at ``T_N`` against
the exact multiplier), the quantity in which the paper warns of index-3
chattering.

>>> import numpy as np
>>> t = np.linspace(0, 1, 101)[1:, None]
>>> ref = np.sin(2 * np.pi * t)
>>> round(float(nrmse(ref, ref + 0.01)), 6)  # a constant offset: 0.01 / standard deviation = 0.01 * sqrt(2)
0.014142
"""

from __future__ import annotations

import numpy as np

__all__ = ["nrmse", "nrmse_of_errors", "variances", "ratio_root", "VARIABLES"]


#: Names of the variables compared by Eq. (72), in the order of the last axis.
VARIABLES = ("x1", "x2", "v1", "v2")


# --------------------------------------------------------------------------- Eq. (72)
def nrmse(reference, numerical):
    """Normalised root-mean-square error of Eq. (72) (see the module docstring).

    Parameters
    ----------
    reference, numerical : arrays ``(..., N_total, n_var)``: the samples at
        ``T_1 ... T_N_total`` (axis -2) of each compared variable (axis -1),
        for Eq. (72) ``(x1, x2, v1, v2)``.

    Returns
    -------
    ``sqrt(sum_j sum_N (ref - num)^2 / sum_N (ref - mean_N ref)^2)`` over the
    leading axes; NaN where the numerical values are not finite.
    """
    ref = np.asarray(reference, dtype=float)
    num = np.asarray(numerical, dtype=float)
    if ref.shape != num.shape:
        raise ValueError(f"reference and numerical must have the same shape, got {ref.shape} and {num.shape}")
    return nrmse_of_errors(ref, ref - num)


def nrmse_of_errors(reference, errors, *, rows=None):
    """Eq. (72) from the errors ``reference - numerical`` themselves.

    This is how the floor-free study uses it (:mod:`icosim.studies.convergence.errors`
    computes the errors directly, never as a difference of two O(1) numbers).
    ``rows`` (a slice or mask over axis -2) restricts the numerator's sum to
    part of the run -- the denominators stay those of the whole run, so the
    squares of the parts add up to the square of the whole.
    """
    ref = np.asarray(reference, dtype=float)
    err = np.asarray(errors, dtype=float)
    if ref.shape != err.shape:
        raise ValueError(f"reference and errors must have the same shape, got {ref.shape} and {err.shape}")
    if rows is not None:
        err = err[..., rows, :]
    with np.errstate(over="ignore", invalid="ignore"):
        return ratio_root(np.sum(err**2, axis=-2), variances(ref))


def variances(reference):
    """Eq. (72)'s denominators: ``sum_N (y_j(T_N) - y_j,mean)^2`` per variable (axis -1)."""
    ref = np.asarray(reference, dtype=float)
    if ref.ndim < 2 or ref.shape[-2] < 2:
        raise ValueError("need at least two time samples (axis -2) per variable")
    variance = np.sum((ref - ref.mean(axis=-2, keepdims=True)) ** 2, axis=-2)
    if np.any(variance <= 0):
        raise ValueError("a reference variable is constant: its NRMSE denominator is zero")
    return variance


def ratio_root(squared_error_sums, variance):
    """``sqrt(sum_j S_j / V_j)`` over the last axis; NaN where not finite."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = np.sqrt(np.sum(np.asarray(squared_error_sums, float) / variance, axis=-1))
    return np.where(np.isfinite(out), out, np.nan)
