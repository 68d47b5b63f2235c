"""A scene of signal connections is checked before any unit is opened: each bad key, name or number refused naming
the key and what is allowed (the units named here need not exist)."""

from __future__ import annotations

import pytest
import yaml

from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.scene import load_scene

BASE = {
    "subsystems": {"a": {"fmu": "a.fmu"}, "b": {"fmu": "b.fmu"}},
    "connections": [{"from": "a.y", "to": "b.u"}, {"from": "b.y", "to": "a.u", "factor": 2.0, "offset": 1.0}],
    "coupling": {"H": 0.1},
    "t_end": 1.0,
}


def load(tmp_path, **changes):
    data = {**BASE, **changes}
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_scene(path)


def test_a_scene_of_connections_defaults_to_held_inputs_and_jacobi(tmp_path):
    scene = load(tmp_path)
    assert scene.connections == [("a", "y", "b", "u", 1.0, 0.0), ("b", "y", "a", "u", 2.0, 1.0)]
    assert (scene.coupling["k"], scene.scheme.name, scene.n_steps) == (0, "jacobi", 10)
    gs = load(tmp_path, coupling={"H": 0.1, "k": 2, "scheme": "gauss-seidel", "order": ["b", "a"]})
    assert gs.scheme.name == "gauss-seidel-21"


@pytest.mark.parametrize("changes, where, says", [
    ({"coupling": {"H": 0.1, "implicit": 1}}, "coupling.implicit", "must be true or false"),
    ({"coupling": {"H": 0.1, "method": "baumgarte"}}, "coupling.method", "allowed: k, scheme, order, H"),
    ({"coupling": {"H": 0.1, "scheme": "gauss-seidel"}}, "coupling.order", "every subsystem once"),
    ({"coupling": {"H": 0.1, "k": -1}}, "coupling.k", "must be an integer 0 .."),
    ({"connections": [{"from": "c.y", "to": "b.u"}]}, "connections[0].from", "with a subsystem of a, b"),
    ({"connections": [{"from": "a.y", "to": "b.u", "gain": 2}]}, "connections[0].gain", "allowed: from, to, factor"),
    ({"connections": [{"from": "a.y", "to": "b.u"}, {"from": "a.z", "to": "b.u"}]}, "connections[1].to",
     "fed already by connections[0]"),
    ({"subsystems": {"a": {"fmu": "a.fmu", "force": "F"}, "b": {"fmu": "b.fmu"}}}, "subsystems.a.force",
     "allowed: fmu, start, interface, tolerance, record"),
    ({"t_end": 1.05}, "t_end", "whole number"),
])  # fmt: skip
def test_bad_input_is_refused_naming_the_key_and_what_is_allowed(tmp_path, changes, where, says):
    with pytest.raises(SceneError) as refused:
        load(tmp_path, **changes)
    assert f"scene.yaml: {where}:" in str(refused.value) and says in str(refused.value), str(refused.value)


def test_a_coupling_history_of_the_wrong_shape_is_refused_before_a_unit_is_opened(tmp_path):
    """k + 1 points of every connection (the units named here do not exist: nothing is opened)."""
    from icosim.problems.fmu.signal_scene import run_signal_scene

    scene = load(tmp_path, coupling={"H": 0.1, "k": 1})
    with pytest.raises(SceneError, match=r"coupling history must be \(2, 2\) .*got \(1, 2\)"):
        run_signal_scene(scene, history=[[0.0, 0.0]])
