"""Coupling methods and decompositions (Sect. 2).

A **decomposition** says which coupling variables exist and which coupling
conditions close the system:

========  ==========================  =====================================
name      coupling variables ``e``    conditions solved in step 2
========  ==========================  =====================================
``ff``    ``lambda``                  constraint (position/velocity/acc.)
``fd``    ``lambda``, ``a_tilde_1``   constraint and ``mu_2 - lambda = 0``
``dd``    ``a_tilde``                 ``mu_2 - mu_1 = 0``
========  ==========================  =====================================

A **method** is a small rule for forming the corrected coupling variables
from the predicted residuals ``r`` and their (constant, Eq. 13/39/63)
sensitivities ``J = dr/de``: each of its *solves* picks a combination of the
constraint levels, stacks it with the force-balance rows and solves the
linearised conditions for ``delta e``; the corrected variables are
``e_p + sum_s w_s delta e_s``.

* Baumgarte (Eqs. 7c, 14-16, 41-43): one solve with levels
  ``(1, beta, gamma)``.  Index 1: ``beta = 2 mu, gamma = mu^2``; index 2:
  ``gamma = 0``; index 3: ``beta = gamma = 0``.
* Weighted multiplier (Eqs. 24-27, 47-53): three solves on position,
  velocity and acceleration level with weights ``(1, a, b)/(1 + a + b)``.
  Index 2: ``b = 0``; index 3: ``a = b = 0``, which is the index-3 Baumgarte
  method term for term.
* Projection (Sects. 2.1.3, 2.2.3, 2.3.1): one solve on acceleration level,
  then the mass-weighted projection of positions and velocities (Eq. 30).

Decision (the paper leaves it out, Sect. 2.3): Baumgarte and the weighted
multiplier are refused with ``dd`` because they would need the kinematics
prescribed on position level, i.e. at least quadratic polynomials.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from .model import ParameterError

__all__ = [
    "METHODS",
    "DECOMPOSITIONS",
    "Decomposition",
    "CouplingMethod",
    "baumgarte",
    "weighted_multiplier",
    "projection",
    "make_method",
    "solve_small",
]

METHODS = ("baumgarte", "weighted", "projection")


@dataclass(frozen=True)
class Decomposition:
    """Which subsystem is force- or kinematically driven, and by which variable."""

    name: str
    kinds: tuple[str, str]  # subsystem 1, subsystem 2
    inputs: tuple[int, int]  # index into e driving each subsystem
    variables: tuple[str, ...]  # names of the coupling variables e
    long_name: str

    @property
    def n_coupling(self) -> int:
        return len(self.variables)

    @property
    def has_constraint_condition(self) -> bool:
        """Is the joint constraint itself one of the conditions (ff, fd)?"""
        return "force" in self.kinds

    @property
    def has_force_balance(self) -> bool:
        """Must multipliers of a kinematic subsystem balance (fd, dd)?"""
        return "kinematic" in self.kinds


DECOMPOSITIONS = {
    "ff": Decomposition("ff", ("force", "force"), (0, 0), ("lambda_c",), "force/force"),
    "fd": Decomposition("fd", ("force", "kinematic"), (0, 1), ("lambda_c", "a_tilde_1"), "force/displacement"),
    "dd": Decomposition("dd", ("kinematic", "kinematic"), (0, 0), ("a_tilde",), "displacement/displacement"),
}


def get_decomposition(name: str) -> Decomposition:
    try:
        return DECOMPOSITIONS[name]
    except KeyError:
        raise ParameterError(f"decomposition must be one of {', '.join(DECOMPOSITIONS)}, got {name!r}") from None


@dataclass(frozen=True)
class CouplingMethod:
    """A rule for the corrected coupling variables (plus optional projection).

    ``solves`` is a tuple of ``(weight, (w_pos, w_vel, w_acc))``.
    ``params`` records the method parameters under their command-line names.
    """

    name: str
    solves: tuple
    projection: bool = False
    params: dict = field(default_factory=dict)

    def check_decomposition(self, decomposition: Decomposition):
        if self.name in ("baumgarte", "weighted") and not decomposition.has_constraint_condition:
            raise ParameterError(
                f"method {self.name!r} is not defined for decomposition "
                f"{decomposition.name!r}: with displacement/displacement coupling the kinematics "
                "would have to be prescribed on position level, which needs at least quadratic "
                "approximation polynomials; the paper treats only projection there (Sect. 2.3). "
                "Use --method projection or --decomposition ff/fd."
            )

    def corrected_coupling(self, e_pred, residuals, jacobians, backend):
        """``e_p + sum_s w_s delta_e_s`` from the linearised coupling conditions.

        ``residuals[level]`` has shape ``(..., n_level)`` and ``jacobians[level]``
        shape ``(..., n_level, n_e)``, levels ``pos``, ``vel``, ``acc``
        (constraint) and ``force`` (force balance, possibly empty).
        """
        total = None
        for weight, levels in self.solves:
            if weight == 0:
                continue  # an unused level may be singular (e.g. velocity at k = 0)
            r = _conditions(levels, residuals, axis=-1)
            J = _conditions(levels, jacobians, axis=-2)
            de = solve_small(J, -r)
            term = de if weight == 1 else backend.const(weight) * de
            total = term if total is None else total + term
        return e_pred + total

    def condition_residuals(self, residuals):
        """The conditions of every solve of this method, concatenated.

        After a converged corrector they vanish for Baumgarte (``g + beta g' +
        gamma g''``) and projection (acceleration level); the weighted
        multiplier's result is a weighted mean of three solutions and satisfies
        none of its three conditions on its own.
        """
        rows = [_conditions(levels, residuals, axis=-1) for weight, levels in self.solves if weight != 0]
        return np.concatenate(rows, axis=-1)


def _conditions(levels, parts, axis):
    """Stack the constraint-level combination and the force-balance rows.

    ``parts`` maps ``pos``/``vel``/``acc``/``force`` to residuals (rows on the
    last axis) or Jacobians (rows on axis -2); ``levels`` are the weights of
    the three constraint levels.
    """
    rows = []
    if parts["pos"].shape[axis]:
        combined = None
        for w, key in zip(levels, ("pos", "vel", "acc")):
            if w == 0:
                continue
            term = parts[key] if w == 1 else w * parts[key]
            combined = term if combined is None else combined + term
        rows.append(combined)
    if parts["force"].shape[axis]:
        rows.append(parts["force"])
    return rows[0] if len(rows) == 1 else np.concatenate(rows, axis=axis)


def solve_small(J, b):
    """Solve ``J x = b`` for stacks of small systems, float64 or mpmath objects.

    Sizes 1 and 2 use closed forms, so a singular point yields inf/nan for that
    point only instead of aborting a whole grid (the precision policy then
    catches it).  Larger systems use LU (numpy) or mpmath's ``lu_solve``.
    """
    n = J.shape[-1]
    J, b = np.broadcast_arrays(J, b[..., None])
    b = b[..., 0]
    if n == 1:
        return b / J[..., 0]
    if n == 2:
        a, bb, c, d = J[..., 0, 0], J[..., 0, 1], J[..., 1, 0], J[..., 1, 1]
        det = a * d - bb * c
        x0 = (d * b[..., 0] - bb * b[..., 1]) / det
        x1 = (a * b[..., 1] - c * b[..., 0]) / det
        return np.stack([x0, x1], axis=-1)
    if J.dtype != object:
        return np.linalg.solve(J, b[..., None])[..., 0]
    out = np.empty(b.shape, dtype=object)
    for idx in np.ndindex(b.shape[:-1]):
        out[idx] = _gauss(J[idx].tolist(), b[idx].tolist())
    return out


def _gauss(A, y):
    """Gaussian elimination with partial pivoting in the numbers' own arithmetic
    (so mpmath values keep their context's precision)."""
    n = len(y)
    A = [row[:] + [y[i]] for i, row in enumerate(A)]
    for col in range(n):
        piv = max(range(col, n), key=lambda r: abs(A[r][col]))
        A[col], A[piv] = A[piv], A[col]
        for r in range(col + 1, n):
            f = A[r][col] / A[col][col]
            A[r] = [a - f * p for a, p in zip(A[r], A[col])]
    x = [None] * n
    for r in range(n - 1, -1, -1):
        x[r] = (A[r][n] - sum(A[r][c] * x[c] for c in range(r + 1, n))) / A[r][r]
    return x


def _finite(name, value):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v):
        raise ParameterError(f"{name} must be a finite number, got {value!r}")
    return v


def baumgarte(beta: float = None, gamma: float = None, *, mu: float = None, index: int = None):
    """Baumgarte stabilisation (Eq. 7c) with dimensionless ``beta``, ``gamma``.

    Give either ``beta`` and ``gamma``, or ``index`` (1, 2, 3) with ``mu`` for
    indices 1 and 2: index 1 ``beta = 2 mu, gamma = mu^2``; index 2
    ``beta = 2 mu, gamma = 0``; index 3 ``beta = gamma = 0``.
    """
    if index is not None:
        if beta is not None or gamma is not None:
            raise ParameterError("give either --index (with --mu) or --beta/--gamma, not both")
        if index not in (1, 2, 3):
            raise ParameterError(f"index must be 1, 2 or 3, got {index!r}")
        if index == 3:
            if mu is not None:
                raise ParameterError("mu is not used at index 3 (beta = gamma = 0); drop --mu")
            beta, gamma = 0.0, 0.0
        else:
            if mu is None:
                raise ParameterError(f"Baumgarte index {index} needs --mu")
            mu = _finite("mu", mu)
            if mu <= 0:
                raise ParameterError(f"mu must be > 0, got {mu!r}")
            beta, gamma = 2 * mu, (mu * mu if index == 1 else 0.0)
    else:
        if mu is not None:
            raise ParameterError("--mu needs --index (1 or 2) for the Baumgarte method")
        if beta is None or gamma is None:
            raise ParameterError("Baumgarte needs --beta and --gamma, or --index (and --mu)")
        beta, gamma = _finite("beta", beta), _finite("gamma", gamma)
        if beta < 0 or gamma < 0:
            raise ParameterError(f"beta and gamma must be >= 0, got beta={beta!r}, gamma={gamma!r}")
    params = {"beta": beta, "gamma": gamma}
    if mu is not None:
        params["mu"] = mu
    params["index"] = index if index is not None else (3 if beta == gamma == 0 else 2 if gamma == 0 else 1)
    return CouplingMethod("baumgarte", ((1, (1, beta, gamma)),), params=params)


def weighted_multiplier(a: float = None, b: float = None, *, index: int = None):
    """Weighted multiplier approach (Eq. 24/53) with weights ``a``, ``b`` >= 0.

    ``index=2`` sets ``b = 0`` (``a`` required), ``index=3`` sets ``a = b = 0``.
    """
    if index is not None:
        if index not in (1, 2, 3):
            raise ParameterError(f"index must be 1, 2 or 3, got {index!r}")
        if index == 3:
            if a not in (None, 0) or b not in (None, 0):
                raise ParameterError("index 3 means a = b = 0; drop --a/--b")
            a, b = 0.0, 0.0
        elif index == 2:
            if b not in (None, 0):
                raise ParameterError("index 2 means b = 0; drop --b")
            if a is None:
                raise ParameterError("weighted multiplier index 2 needs --a")
            b = 0.0
        elif a is None or b is None:
            raise ParameterError("weighted multiplier index 1 needs --a and --b")
    if a is None or b is None:
        raise ParameterError("weighted multiplier needs --a and --b (or --index)")
    a, b = _finite("a", a), _finite("b", b)
    if a < 0 or b < 0:
        raise ParameterError(f"a and b must be >= 0, got a={a!r}, b={b!r}")
    if index is None:
        index = 3 if a == b == 0 else 2 if b == 0 else 1
    elif index == 1 and b == 0:
        raise ParameterError("index 1 needs b > 0 (b = 0 is the index-2 method)")
    # exact rational weights, so that multiprecision runs are not limited by 1/3 in binary
    fa, fb = Fraction(a), Fraction(b)
    s = 1 + fa + fb
    solves = ((1 / s, (1, 0, 0)), (fa / s, (0, 1, 0)), (fb / s, (0, 0, 1)))
    return CouplingMethod("weighted", solves, params={"a": a, "b": b, "index": index})


def projection():
    """Acceleration-level correction followed by the mass-weighted projection."""
    return CouplingMethod("projection", ((1, (0, 0, 1)),), projection=True, params={"index": 1})


def make_method(name: str, **params) -> CouplingMethod:
    """Build a method by name; ``params`` as for the functions above (None = not given)."""
    params = {k: v for k, v in params.items() if v is not None}
    if name == "baumgarte":
        allowed = {"beta", "gamma", "mu", "index"}
        factory = baumgarte
    elif name == "weighted":
        allowed = {"a", "b", "index"}
        factory = weighted_multiplier
    elif name == "projection":
        allowed = set()
        factory = projection
    else:
        raise ParameterError(f"method must be one of {', '.join(METHODS)}, got {name!r}")
    extra = sorted(set(params) - allowed)
    if extra:
        raise ParameterError(
            f"parameter(s) {', '.join(extra)} not used by method {name!r}"
            + (f" (it takes {', '.join(sorted(allowed))})" if allowed else " (it takes none)")
        )
    return factory(**params)
