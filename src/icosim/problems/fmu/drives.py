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

import numpy as np

from .errors import SceneError

__all__ = ["DRIVE_KEYS", "KINEMATICS", "DrivenPoints", "drive_rows", "is_drive", "prescribed_end", "role_keys"]

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


def role_keys(path, data, graph, i, method, projects, driven) -> tuple:
    """The variable keys subsystem ``i`` of a scene needs for its kind (``graph.port_kind``), ``projects``: with
    a projection; a drive's keys checked against its joint partner's (``driven``: the joint that drives it, for
    a message).  What cannot be served raises :class:`~icosim.problems.fmu.errors.SceneError` naming the key."""
    names = list(data["subsystems"])
    name, sub = names[i], data["subsystems"][names[i]]
    kind = graph.port_kind(i, 0)

    def fail(key, message):
        raise SceneError(f"{path}: subsystems.{name}{'.' + key if key else ''}: {message}")

    if kind == "force":
        extra = [k for k in DRIVE_KEYS if k in sub]
        if extra:
            fail(
                extra[0],
                f"subsystem {name} is force-driven in {driven}: only a kinematically driven one takes a drive's inputs",
            )
        return ("force", *KINEMATICS) + (("mass", "set_position", "set_velocity") if projects else ())
    if not any(k in sub for k in DRIVE_KEYS):
        fail(
            "acceleration_input",
            f"required: subsystem {name} is kinematically driven in {driven} (name of the "
            f"prescribed-acceleration input; a drive takes any of {', '.join(DRIVE_KEYS)})",
        )
    if not (any(k in sub for k in DRIVE_KEYS[:2]) or any(k not in sub for k in KINEMATICS)):
        return ("acceleration_input", "reaction_force") + (("mass", "set_position", "set_velocity") if projects else ())
    jt = graph.joints[graph.joints_of(i)[0]]
    other = jt.second if jt.first == i else jt.first
    partner, both = data["subsystems"][names[other]], graph.port_kind(other, 0) == "kinematic"
    missing = [k for k in KINEMATICS[:2] if both and k not in sub and k not in partner]
    if missing:
        fail(
            missing[0],
            f"required: neither {name} nor {names[other]} (both kinematically driven) has a "
            f"{missing[0]} output, so nothing says where their joint is",
        )
    if projects and both and "mass" not in sub and "mass" not in partner:
        fail(
            "mass",
            f"required: method {method} projects onto the joint of two drives, {name} and {names[other]}, "
            "and neither has a mass (the projection's weight)",
        )
    # a drive's point follows the joint where the unit has no output for it (weight 0, no setter needed)
    setters = (("position", "set_position"), ("velocity", "set_velocity"))
    return ("reaction_force",) + (tuple(setter for k, setter in setters if k in sub) if projects else ())


class DrivenPoints:
    """The drives of a :class:`~icosim.problems.fmu.problem.FmuCosimulation` (a mixin: it uses the problem's units,
    graph, committed state, ``H``, ``time`` and ``_drives``, ``_outputs``, ``_output_keys``, ``_to_start``):
    ``_drives[i]`` is None, or unit ``i``'s drive inputs and the kinematic outputs it has."""

    def _drive_entries(self) -> list:
        """Per unit: None, or a drive's inputs and the kinematic outputs it has (the others are prescribed)."""
        return [
            (u.drive_keys, tuple(k for k in KINEMATICS if k in u.elements)) if is_drive(u, c.kind) else None
            for u, c in zip(self.units, self.couplings)
        ]

    def _start_points(self) -> list:
        """Each unit's position and velocity at ``T_0``; a drive's point has its own outputs where it has them,
        else its joint partner's (the joint holds at ``T_0``), and the drive's inputs are set there and its start
        state saved again."""
        n = self.n_dim
        rows = [
            None if d is not None else u.get(("position", "velocity")).ravel() for u, d in zip(self.units, self._drives)
        ]
        for i, drive in enumerate(self._drives):
            if drive is None:
                continue
            jt = self.graph.joints[self.graph.joints_of(i)[0]]
            other = jt.second if jt.first == i else jt.first
            point = []
            for q, key in enumerate(("position", "velocity")):
                if key in drive[1]:
                    point.append(self.units[i].get((key,)).ravel())
                elif self._drives[other] is None:
                    point.append(rows[other][q * n : (q + 1) * n])
                else:  # a drive at the other side too: its own output (the scene asks one of them for it)
                    point.append(self.units[other].get((key,)).ravel())
            rows[i] = np.concatenate(point)
            self._to_start(i)
            self.units[i].set("drive", self._drive_values(i, point[0].tolist(), point[1].tolist(), [0.0] * n))
            self.units[i].free(self._start[i])
            self._start[i] = self.units[i].save()
        return rows

    def _point(self, i):
        """A drive's point at ``T_N`` (position and velocity, lists of floats): the committed state."""
        row = self._committed[i].tolist()
        return row[: self.n_dim], row[self.n_dim :]

    def _drive_values(self, i, x, v, a):
        """A drive's input values (its ``drive`` entry) for the point at ``x``, ``v`` with acceleration ``a``."""
        given = {"position_input": x, "velocity_input": v, "acceleration_input": a}
        return [q for key in self._drives[i][0] for q in given[key]]

    def _merged(self, i, values, x, v, a):
        """A drive's outputs in the order of a kinematic unit's (position, velocity, acceleration, reaction force;
        floats, component after component): its own where it has them (``values``, as read), else ``x``, ``v``,
        ``a`` (prescribed)."""
        n, own = self.n_dim, self._drives[i][1]
        out, at = [], 0
        for key, prescribed in zip(KINEMATICS, (x, v, a)):
            if key in own:
                out += values[at : at + n]
                at += n
            else:
                out += prescribed
        return out + values[at:]

    def _drive_outputs(self, i, x, v, a):
        """A drive at its present state with its point at ``x``, ``v`` and acceleration ``a`` (no step): its end
        and outputs (``_outputs``)."""
        self.units[i].set("drive", self._drive_values(i, x, v, a))
        return self._outputs(i, a, self._merged(i, self.units[i].read(self._output_keys(i)), x, v, a))

    def _drive_at_start(self, i, start, u):
        """Drive ``i``'s outputs at its start, its point at ``start`` (``(2, n)``), its acceleration ``u``."""
        self._to_start(i)
        return self._drive_outputs(i, start[0].tolist(), start[1].tolist(), np.asarray(u, dtype=float).tolist())[1]

    def _drive_step(self, i, coef, h, step_index, restore=None):
        """Drive ``i`` over ``[T_N, T_N + h]`` from its point at ``T_N`` with the acceleration coefficients
        ``coef`` (rows of floats), after restoring ``restore`` where given: its end and outputs."""
        x0, v0 = self._point(i)
        rows = drive_rows(self._drives[i][0], coef, x0, v0, h)
        values = self.units[i].advance(
            "drive", rows, self.time, h, step_index=step_index, restore=restore, read=self._output_keys(i)
        )
        end = prescribed_end(coef, x0, v0, h)
        return self._outputs(i, end[2], self._merged(i, values.ravel().tolist(), *end))
