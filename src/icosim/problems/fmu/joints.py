"""A scene's joints and Gauss-Seidel order checked against its subsystems, and its scheme against its units'
feedthrough: the part of a scene that the joints make (:mod:`icosim.problems.fmu.scene` reads the file).

A joint names its two subsystems, first and second; each unit has one joint point, so all of its joints attach
there, a kinematically driven unit follows one joint only, and the joints form a tree (a loop would repeat a
condition of the others).
"""

from __future__ import annotations

from ...engine.graph import CouplingGraph, Joint
from ...engine.schema import schema_defs
from ...engine.schemes import SCHEMES, get_scheme, standard_schemes
from ...engine.stages import plan
from ...errors import ParameterError
from .errors import FmuError, SceneError

__all__ = ["ORDERED_SCHEMES", "scene_joints", "check_order", "check_scheme", "joint_schema", "graph_message"]

#: Scheme names that take ``coupling.order`` (the subsystems' names in the order they advance).
ORDERED_SCHEMES = ("gauss-seidel", "gauss-seidel-as-integrated")

#: A Gauss-Seidel order by the subsystems' numbers in file order (dots between numbers from ten subsystems).
NUMBERED = r"^gauss-seidel-[0-9]+(\.[0-9]+)*(-as-integrated)?$"


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def joint_schema(name: dict, decomposition: dict) -> dict:
    """The JSON schema of one ``joints`` entry: ``name`` that of a subsystem's name, ``decomposition`` the
    registry's."""
    return {
        "type": "object",
        "additionalProperties": False,
        "required": ["between", "decomposition"],
        "properties": {
            "between": {"type": "array", "items": name, "minItems": 2, "maxItems": 2},
            "decomposition": decomposition,
        },
    }


def graph_message(where: str, err, data) -> str | None:
    """The message for a schema error ``err`` at ``where`` about joints, the scheme or its order (None: not one
    of those)."""
    if where == "coupling.scheme" and err.validator in ("anyOf", "enum", "type", "pattern"):
        return (
            f"{err.instance!r} is not allowed; allowed: {', '.join(SCHEMES)}, gauss-seidel-<the subsystems' numbers "
            f"in file order> (e.g. gauss-seidel-312; dots between numbers from ten subsystems), or "
            f"{' or '.join(ORDERED_SCHEMES)} with coupling.order"
        )
    if where == "coupling" and err.validator == "not":
        return (
            "decomposition is not allowed with joints: each joint has its own (joints[].decomposition, one of "
            f"{', '.join(schema_defs()['decomposition']['enum'])})"
        )
    if where == "coupling" and err.validator == "required" and "'decomposition'" in err.message:
        return (
            f"{err.message} without joints (the decomposition of the two subsystems' joint, one of "
            f"{', '.join(schema_defs()['decomposition']['enum'])}); or join the subsystems by joints"
        )
    if where == "subsystems" and err.validator == "maxProperties":
        return (
            f"{len(err.instance)} subsystems ({', '.join(err.instance)}): a scene without joints couples exactly "
            "two (the paper's subsystems 1 and 2); join more by joints: [{between: [a, b], decomposition: ff}, ...]"
        )
    if err.validator == "uniqueItems":
        seen: set = set()
        twice = [x for x in err.instance if x in seen or seen.add(x)]
        subs = data.get("subsystems") if isinstance(data.get("subsystems"), dict) else {}
        return f"names {', '.join(map(str, dict.fromkeys(twice)))} more than once; each subsystem once" + (
            f" ({', '.join(subs)})" if subs else ""
        )
    return None


def scene_joints(path, data, names) -> tuple:
    """The scene's ``joints`` as :class:`~icosim.engine.graph.Joint` s (empty without the key), refusing a name
    that is no subsystem, a subsystem in no joint, joints that leave subsystems apart or close a loop, and a
    kinematically driven subsystem in more than one joint."""
    if "joints" not in data:
        return ()
    allowed = ", ".join(names)
    out = []
    root = list(range(len(names)))

    def find(a):
        while root[a] != a:
            a = root[a]
        return a

    for j, entry in enumerate(data["joints"]):
        first, second = entry["between"]
        for who in (first, second):
            if who not in names:
                _fail(path, f"joints[{j}].between", f"{who!r} is not a subsystem; the subsystems: {allowed}")
        if first == second:
            _fail(path, f"joints[{j}].between", f"names {first} twice; a joint joins two different subsystems")
        a, b = names.index(first), names.index(second)
        for k, earlier in enumerate(out):
            if {earlier.first, earlier.second} == {a, b}:
                _fail(path, f"joints[{j}].between", f"{first} and {second} are joined already by joints[{k}]")
        if find(a) == find(b):
            _fail(
                path,
                f"joints[{j}].between",
                f"{first} and {second} are joined already through the joints before it (a loop): a unit has one "
                "joint point, so a loop repeats a condition of the others (the corrector's linear system is "
                "singular); remove a joint of the loop",
            )
        root[find(a)] = find(b)
        out.append(Joint(a, b, entry["decomposition"]))
    used = {i for jt in out for i in (jt.first, jt.second)}
    alone = [n for i, n in enumerate(names) if i not in used]
    if alone:
        _fail(
            path,
            "joints",
            f"{'subsystem ' if len(alone) == 1 else 'subsystems '}{', '.join(alone)} "
            f"{'takes' if len(alone) == 1 else 'take'} part in no joint; every subsystem must be joined "
            f"(joints: [{{between: [{alone[0]}, ...], decomposition: ff}}, ...])",
        )
    groups: dict[int, list[str]] = {}
    for i, n in enumerate(names):
        groups.setdefault(find(i), []).append(n)
    if len(groups) > 1:
        parts = "; ".join(", ".join(g) for g in groups.values())
        _fail(
            path,
            "joints",
            f"the joints do not connect every subsystem: they make {len(groups)} separate groups ({parts}); "
            "join the groups (a scene is one connected system)",
        )
    for j, jt in enumerate(out):
        for side, i in enumerate((jt.first, jt.second)):
            if jt.decomposition.kinds[side] != "kinematic":
                continue
            others = [k for k, o in enumerate(out) if k != j and i in (o.first, o.second)]
            if others:
                _fail(
                    path,
                    f"joints[{j}].decomposition",
                    f"{jt.decomposition.name} drives {names[i]} kinematically, but {names[i]} takes part in "
                    f"joints[{others[0]}] too: a kinematically driven unit follows one joint only (its prescribed "
                    f"acceleration is that joint's); make {names[i]} force driven in joints[{j}] "
                    f"({_force_side(jt.decomposition.name, side)}), or join it by this joint only",
                )
    return tuple(out)


def _force_side(decomposition: str, side: int) -> str:
    """The decompositions whose ``side`` is force driven and whose other side is as in ``decomposition``."""
    other = decomposition[1 - side]
    return "f" + other if side == 0 else other + "f"


def check_order(path, c: dict, scene, graph: CouplingGraph, method) -> None:
    """The scheme against the scene: ``coupling.order`` with ``gauss-seidel`` (every subsystem once), a numbered
    order of as many subsystems as the scene has, and an order the stages can serve with the method
    (:func:`icosim.engine.stages.plan`)."""
    names = list(scene.names)
    given = c.get("scheme", "jacobi")
    allowed = ", ".join(names)
    if given in ORDERED_SCHEMES:
        if "order" not in c:
            _fail(
                path,
                "coupling.order",
                f"required with scheme {given}: the subsystems' names in the order they advance, each once "
                f"(e.g. order: [{allowed}])",
            )
        order = c["order"]
        for who in order:
            if who not in names:
                _fail(path, "coupling.order", f"{who!r} is not a subsystem; the subsystems: {allowed}")
        missing = [n for n in names if n not in order]
        if missing:
            _fail(
                path,
                "coupling.order",
                f"misses {', '.join(missing)}: the order names every subsystem once ({allowed})",
            )
        key = "coupling.order"
    else:
        if "order" in c:
            _fail(
                path,
                "coupling.order",
                f"only with scheme {' or '.join(ORDERED_SCHEMES)}; scheme {given} does not take an order",
            )
        key = "coupling.scheme"
        try:
            numbers = getattr(get_scheme(given), "order", None)
        except ParameterError as exc:
            every = _numbered(range(1, len(names) + 1))
            _fail(
                path,
                key,
                f"{exc}; allowed: {', '.join(SCHEMES)}, gauss-seidel-<order> naming each of the {len(names)} "
                f"subsystems once by its number in file order (e.g. gauss-seidel-{every}), or scheme: gauss-seidel "
                f"with order: [{allowed}]",
            )
        if numbers is not None and len(numbers) != len(names):
            _fail(
                path,
                key,
                f"{given} orders {len(numbers)} subsystems, the scene has {len(names)} ({allowed}, numbered in "
                f"file order); use gauss-seidel-{_numbered(range(1, len(names) + 1))}-style numbers of all of "
                f"them, or scheme: gauss-seidel with order: [{allowed}]",
            )
    try:
        plan(scene.scheme, graph, method)
    except ParameterError as exc:
        hint = ""
        if scene.has_joints and "order" in key:
            hint = f"; by name, e.g. order: [{', '.join(names[i] for i in breadth_first(graph, 0))}]"
        _fail(path, key, f"{exc}{hint}")


def _numbered(numbers) -> str:
    numbers = list(numbers)
    return ("" if len(numbers) < 10 else ".").join(map(str, numbers))


def driven_by(scene, graph: CouplingGraph, i: int) -> str:
    """Which joint drives subsystem ``i`` as it is driven (for a message)."""
    if not scene.has_joints:
        return f"decomposition {graph.joints[0].decomposition.name}"
    j = graph.joints_of(i)[0]
    return scene.joint_label(j)


def check_scheme(scene, units, couplings, graph):
    """Refuse a scheme that re-evaluates a finished unit without a step where that unit's output follows its input
    only through a step, naming the schemes that would not."""
    scheme = scene.scheme
    for i in plan(scheme, graph).reevaluated:
        if not couplings[i].feedthrough:
            out = "acceleration" if couplings[i].kind == "force" else "drive's force"
            label = units[i].label
            if scene.has_joints:
                # a unit is re-evaluated when a neighbour advances after it: last among its neighbours it is not
                later = [scene.names[o] for o in graph.neighbours(i) if _position(scheme, o) > _position(scheme, i)]
                order = [scene.names[o] for o in reversed(breadth_first(graph, i))]
                key = "coupling.order" if "order" in scene.data["coupling"] else "coupling.scheme"
                use = (
                    f"use jacobi, an order in which {label} advances after its neighbours (e.g. order: "
                    f"[{', '.join(order)}]), or {ORDERED_SCHEMES[1]}"
                )
                what = f"{scene.scheme_text()} re-evaluates {label} (it advances before {', '.join(later)})"
            else:
                others = [n for n in standard_schemes() if i not in plan(get_scheme(n), graph).reevaluated]
                key = "coupling.scheme"
                use = f"use {', '.join(others)} or {scheme.name}-as-integrated"
                what = f"{scheme.name} re-evaluates the leading unit {label}"
            raise FmuError(
                f"{scene.path}: {key}: {what}'s {out} with the corrected coupling variables without a step, but "
                f"{label} has no direct feedthrough (its {out} follows its input only through a step); {use}"
            )


def _position(scheme, i) -> int:
    """When subsystem ``i`` (0-based) advances in ``scheme`` (Jacobi: all at once, 0)."""
    order = getattr(scheme, "order", None)
    return 0 if order is None else list(order).index(i + 1)


def breadth_first(graph: CouplingGraph, start: int) -> list[int]:
    """The subsystems breadth first from ``start``: every subsystem after ``start`` has an earlier neighbour;
    reversed, every subsystem comes after its neighbours farther from ``start``, and ``start`` last."""
    order, seen = [start], {start}
    for i in order:
        for other in graph.neighbours(i):
            if other not in seen:
                seen.add(other)
                order.append(other)
    return order
