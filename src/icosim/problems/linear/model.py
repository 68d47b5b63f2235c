"""The linear two-mass co-simulation test model (paper, Sect. 1 and Eqs. 5, 6, 71).

Two single-mass oscillators joined by a rigid link.  Everything the engine
integrates is expressed in the paper's dimensionless form (Eq. 6): time in
macro steps (``t_bar = t / H``), positions in a reference length ``l = 1``,
velocities ``v_bar = H v``, and the coupling force ``lambda_bar = lambda H^2 / m1``.

Two equivalent descriptions are offered:

* :class:`TestModel` -- the five dimensionless parameters of Eq. (71),
  ``(lr1, li1, am21, alr21, ali21)``; this is what the stability plots use.
* :class:`PhysicalModel` -- ``(m1, m2, c1, c2, d1, d2, H)``; this is what the
  convergence study uses.  It also accepts overdamped subsystems
  (``d^2 > 4 m c``), for which Eq. (71) has no real ``li``.

Both reduce to :class:`Coefficients`: per-unit-mass stiffness and damping of
each subsystem in dimensionless time, plus the mass ratio.  All attributes may
be NumPy arrays (they broadcast), which is how whole parameter grids are
evaluated in one call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ...errors import ParameterError

__all__ = ["Coefficients", "Segment", "TestModel", "PhysicalModel"]


def _check(name: str, value, *, positive=False, nonnegative=False, nonpositive=False):
    if type(value) is float:  # one point (e.g. of a grid, each certified alone): the same checks, no array
        if not math.isfinite(value):
            raise ParameterError(f"{name} must be a finite number, got {value!r}")
        if (positive and not value > 0) or (nonnegative and not value >= 0) or (nonpositive and not value <= 0):
            bound = "> 0" if positive else ">= 0" if nonnegative else "<= 0"
            raise ParameterError(f"{name} must be {bound}, got {value!r}")
        return
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be a finite number, got {value!r}")
    if positive and not np.all(arr > 0):
        raise ParameterError(f"{name} must be > 0, got {value!r}")
    if nonnegative and not np.all(arr >= 0):
        raise ParameterError(f"{name} must be >= 0, got {value!r}")
    if nonpositive and not np.all(arr <= 0):
        raise ParameterError(f"{name} must be <= 0, got {value!r}")


@dataclass(frozen=True)
class Coefficients:
    """Dimensionless subsystem coefficients, the engine's internal form.

    Subsystem i obeys ``v_i' = -k_i x_i - delta_i v_i + g_i f_i`` with the inverse masses ``g_1 = 1`` and
    ``g_2 = 1/am21`` and the coupling forces ``f_1 = lambda``, ``f_2 = -lambda`` (Eq. 7).

    Attributes
    ----------
    k1, delta1 : stiffness ``c1 H^2/m1`` and damping ``d1 H/m1`` of subsystem 1.
    k2, delta2 : stiffness ``c2 H^2/m2`` and damping ``d2 H/m2`` of subsystem 2
        (per unit mass of subsystem 2: ``(alpha_c21/alpha_m21) c1_bar``, Eq. 6).
    am21 : mass ratio ``m2/m1``.
    """

    k1: object
    delta1: object
    k2: object
    delta2: object
    am21: object

    def map(self, fn) -> Coefficients:
        """Apply ``fn`` to every attribute (e.g. to add a broadcasting axis)."""
        return Coefficients(*(fn(getattr(self, f.name)) for f in fields(self)))

    def segments(self, backend) -> tuple[Segment, Segment]:
        """The two single-mass segments, masses ``1`` and ``am21``, in ``backend``'s arithmetic."""
        one = backend.const(1) + 0 * self.am21
        return (
            Segment((one,), ((self.k1,),), ((self.delta1,),)),
            Segment((self.am21,), ((self.k2,),), ((self.delta2,),)),
        )


@dataclass(frozen=True)
class Segment:
    """One linear segment in the engine's dimensionless form: its masses (relative to a reference mass) and
    the stiffness and damping per unit mass, ``stiffness[q][j]`` the force on mass ``q`` per displacement of
    mass ``j`` divided by ``m_q`` (``None`` where structurally zero; arrays broadcast)."""

    masses: tuple
    stiffness: tuple
    damping: tuple

    def map(self, fn) -> Segment:
        """Apply ``fn`` to every coefficient."""

        def rows(matrix):
            return tuple(tuple(None if c is None else fn(c) for c in row) for row in matrix)

        return Segment(tuple(fn(m) for m in self.masses), rows(self.stiffness), rows(self.damping))


@dataclass(frozen=True)
class TestModel:
    """The five independent parameters of Eq. (71).

    Parameters
    ----------
    lr1 : real part of the eigenvalue of subsystem 1, ``-d1_bar/2`` (<= 0).
    li1 : imaginary part of that eigenvalue, ``sqrt(4 c1_bar - d1_bar^2)/2`` (>= 0).
    am21 : mass ratio ``m2/m1`` (> 0).
    alr21 : damping ratio ``lr2/lr1`` (>= 0).
    ali21 : frequency ratio ``li2/li1`` (>= 0).

    The physically meaningful test model is a passive (stable) mechanical
    system, hence the sign conventions above; they are checked on creation.

    Subsystem 1 with eigenvalues ``-0.5 +- 2i`` has ``k1 = 0.25 + 4`` and
    ``delta1 = 1``; a physical realisation gives the same point back:

    >>> m = TestModel(lr1=-0.5, li1=2.0, am21=2.0)
    >>> c = m.coefficients()
    >>> float(c.k1), float(c.delta1)
    (4.25, 1.0)
    >>> back = m.to_physical(m1=3.0, H=0.1).test_model()
    >>> round(back.lr1, 12), round(back.li1, 12), back.am21
    (-0.5, 2.0, 2.0)
    """

    __test__ = False  # not a pytest test class, despite the name

    lr1: object
    li1: object
    am21: object = 1.0
    alr21: object = 1.0
    ali21: object = 1.0

    def __post_init__(self):
        _check("lr1", self.lr1, nonpositive=True)
        _check("li1", self.li1, nonnegative=True)
        _check("am21", self.am21, positive=True)
        _check("alr21", self.alr21, nonnegative=True)
        _check("ali21", self.ali21, nonnegative=True)

    @property
    def lr2(self):
        return self.alr21 * self.lr1

    @property
    def li2(self):
        return self.ali21 * self.li1

    def coefficients(self) -> Coefficients:
        """Subsystem coefficients: ``k = lr^2 + li^2``, ``delta = -2 lr``."""
        return eq71_coefficients(self.lr1, self.li1, self.am21, self.alr21, self.ali21)

    def to_physical(self, m1: float = 1.0, H: float = 1.0) -> PhysicalModel:
        """One physical realisation (mass ``m1`` and macro step ``H`` are free scales)."""
        c = self.coefficients()
        m2 = self.am21 * m1
        return PhysicalModel(
            m1=m1,
            m2=m2,
            c1=c.k1 * m1 / H**2,
            c2=c.k2 * m2 / H**2,
            d1=c.delta1 * m1 / H,
            d2=c.delta2 * m2 / H,
            H=H,
        )


def eq71_coefficients(lr1, li1, am21, alr21, ali21) -> Coefficients:
    """:meth:`TestModel.coefficients` of parameters in any arithmetic, unchecked (the same operations).

    For values a :class:`TestModel` was already checked with, e.g. its parameters as balls
    (:mod:`icosim.engine.spectral.certified`), without checking each again.
    """
    lr2, li2 = alr21 * lr1, ali21 * li1
    return Coefficients(
        k1=lr1**2 + li1**2,
        delta1=-2 * lr1,
        k2=lr2**2 + li2**2,
        delta2=-2 * lr2,
        am21=am21,
    )


@dataclass(frozen=True)
class PhysicalModel:
    """Masses, spring constants, damping coefficients and macro-step size.

    Any non-negative stiffness and damping is accepted, overdamped included.
    """

    m1: object
    m2: object
    c1: object
    c2: object
    d1: object
    d2: object
    H: object

    def __post_init__(self):
        for name in ("m1", "m2", "H"):
            _check(name, getattr(self, name), positive=True)
        for name in ("c1", "c2", "d1", "d2"):
            _check(name, getattr(self, name), nonnegative=True)

    def coefficients(self) -> Coefficients:
        """Dimensionless coefficients of Eq. (5)/(6) (valid for any damping)."""
        return Coefficients(
            k1=self.c1 * self.H**2 / self.m1,
            delta1=self.d1 * self.H / self.m1,
            k2=self.c2 * self.H**2 / self.m2,
            delta2=self.d2 * self.H / self.m2,
            am21=self.m2 / self.m1,
        )

    @property
    def overdamped(self):
        """Per subsystem: True where ``d^2 > 4 m c`` (no real Eq. (71) form)."""
        return (
            np.asarray(self.d1) ** 2 > 4 * np.asarray(self.m1) * np.asarray(self.c1),
            np.asarray(self.d2) ** 2 > 4 * np.asarray(self.m2) * np.asarray(self.c2),
        )

    def test_model(self) -> TestModel:
        """The Eq. (71) parameters; refused for overdamped subsystems.

        ``alr21`` and ``ali21`` are ratios; where subsystem 1 has no damping
        (``lr1 = 0``) or no oscillation (``li1 = 0``) the ratio is undefined and
        is refused unless subsystem 2 has the same property (then it is 1).
        """
        over1, over2 = self.overdamped
        if np.any(over1) or np.any(over2):
            which = "subsystem 1" if np.any(over1) else "subsystem 2"
            raise ParameterError(
                f"{which} is overdamped (d^2 > 4 m c): Eq. (71) needs a real li; "
                "use PhysicalModel.coefficients() directly"
            )
        c = self.coefficients()
        lr1 = -c.delta1 / 2
        li1 = np.sqrt(np.maximum(c.k1 - lr1**2, 0.0))
        lr2 = -c.delta2 / 2
        li2 = np.sqrt(np.maximum(c.k2 - lr2**2, 0.0))
        return TestModel(
            lr1=_scalar(lr1),
            li1=_scalar(li1),
            am21=_scalar(c.am21),
            alr21=_scalar(_ratio("alr21", lr2, lr1)),
            ali21=_scalar(_ratio("ali21", li2, li1)),
        )


def _ratio(name, num, den):
    num, den = np.asarray(num, float), np.asarray(den, float)
    bad = (den == 0) & (num != 0)
    if np.any(bad):
        raise ParameterError(f"{name} is undefined: subsystem 1 has a zero where subsystem 2 has not")
    return np.where(den == 0, 1.0, num / np.where(den == 0, 1.0, den))


def _scalar(x):
    x = np.asarray(x, dtype=float)
    return float(x) if x.ndim == 0 else x
