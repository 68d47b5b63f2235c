"""A kinematically driven unit's drive: what its position, velocity and acceleration inputs follow over a macro step
(docs/fmi.md, "Drives by position, velocity and acceleration").

The coupling variable of a drive is the prescribed acceleration ``a_tilde`` (the paper's index-1 drive, Eqs. 33b,
57): over ``[T_N, T_N+1]`` the driven point's acceleration is the coupling polynomial
``a(tau) = sum_m c_m tau^m`` (``tau = (t - T_N)/H``), and its velocity and position follow by integration from the
driven point's state ``(x_N, v_N)`` at ``T_N``::

    v(tau) = v_N + H sum_m c_m tau^(m+1) / (m+1)
    x(tau) = x_N + H v_N tau + H^2 sum_m c_m tau^(m+2) / ((m+1) (m+2))

A unit takes any of them as inputs (``position_input``, ``velocity_input``, ``acceleration_input``), each a
polynomial in ``tau`` handed to the unit as every other coupling input is (its derivatives at ``T_N``, or its
values at the sub-steps).  Where the unit has no ``position``, ``velocity`` or ``acceleration`` output, the driven
point's is the prescribed one: ``x(1)``, ``v(1)``, ``a(1)``.
"""

from __future__ import annotations

__all__ = ["DRIVE_KEYS", "KINEMATICS", "drive_rows", "is_drive", "prescribed_end"]

#: The inputs a drive may have, in the order their components stand in the unit's ``drive`` entry.
DRIVE_KEYS = ("position_input", "velocity_input", "acceleration_input")

#: The driven point's kinematics (outputs a unit may have; absent: the prescribed ones).
KINEMATICS = ("position", "velocity", "acceleration")


def drive_rows(keys, coef, x0, v0, H) -> list:
    """The monomial coefficients (rows of floats, ``rows[m][q]``) of the drive inputs ``keys`` (a subset of
    :data:`DRIVE_KEYS`, in that order), their components side by side, for the acceleration coefficients ``coef``
    (``coef[m][q]``, ``(k + 1, n)``) from the driven point's position ``x0`` and velocity ``v0`` (``n`` floats each)
    over a macro step of ``H``.  The rows run to the highest degree any of the inputs has (``k + 2`` with a
    position input); the others have zeros there.

    >>> drive_rows(("position_input", "velocity_input", "acceleration_input"), [[2.0]], [1.0], [0.5], 0.5)
    [[1.0, 0.5, 2.0], [0.25, 1.0, 0.0], [0.25, 0.0, 0.0]]
    """
    k1, n = len(coef), len(coef[0])
    parts = []
    for key in keys:
        if key == "position_input":
            rows = [list(x0), [H * v for v in v0]]
            rows += [[H * H * c / ((m + 1) * (m + 2)) for c in coef[m]] for m in range(k1)]
        elif key == "velocity_input":
            rows = [list(v0)] + [[H * c / (m + 1) for c in coef[m]] for m in range(k1)]
        else:
            rows = [list(row) for row in coef]
        parts.append(rows)
    degree = max(len(rows) for rows in parts)
    return [[v for rows in parts for v in (rows[m] if m < len(rows) else [0.0] * n)] for m in range(degree)]


def prescribed_end(coef, x0, v0, H):
    """The driven point's position, velocity and acceleration at ``T_N+1`` (``tau = 1``), lists of ``n`` floats.

    >>> prescribed_end([[2.0]], [1.0], [0.5], 0.5)
    ([1.5], [1.5], [2.0])
    """
    k1 = len(coef)
    x = [x + H * v for x, v in zip(x0, v0)]
    v = list(v0)
    a = [0.0] * len(x0)
    for m in range(k1):
        wx, wv = H * H / ((m + 1) * (m + 2)), H / (m + 1)
        x = [xq + wx * c for xq, c in zip(x, coef[m])]
        v = [vq + wv * c for vq, c in zip(v, coef[m])]
        a = [aq + c for aq, c in zip(a, coef[m])]
    return x, v, a


def is_drive(unit, kind) -> bool:
    """Is a unit driven as ``kind`` a drive whose point the master prescribes: a kinematically driven unit with a
    position or velocity input, or without its own position, velocity or acceleration output (one with only an
    acceleration input and all three outputs integrates its point itself)?"""
    if kind != "kinematic":
        return False
    keys = getattr(unit, "drive_keys", ("acceleration_input",))
    return keys != ("acceleration_input",) or any(k not in unit.elements for k in KINEMATICS)
