"""Inputs fed by a table or a constant (``sources``): the table's values just before and after a point, its chord
over a step, and each bad entry refused naming the key before any unit is opened (the units named need not exist)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_sources import TableSource

BASE = {
    "subsystems": {"a": {"fmu": "a.fmu"}, "b": {"fmu": "b.fmu"}},
    "connections": [{"from": "a.y", "to": "b.u"}],
    "coupling": {"H": 0.1},
    "t_end": 1.0,
}
ROAD = TableSource(np.array([0.0, 0.1, 0.1, 5.0]), np.array([0.0, 0.0, 0.1, 0.1]))  # OMSimulator's road.csv


def test_a_jump_is_taken_at_its_time_and_ends_hold():
    assert (ROAD.before(0.1), ROAD.after(0.1)) == (0.0, 0.1)
    below, above = np.nextafter(0.1, 0.0), np.nextafter(0.1, 1.0)  # t0 + n H rounded a bit off the jump
    assert ROAD.after(below) == ROAD.after(above) == 0.1 and ROAD.before(below) == ROAD.before(above) == 0.0
    assert ROAD.after(0.1 - 1e-9) == 0.0  # not rounding: before the jump
    assert ROAD.after(-1.0) == 0.0 and ROAD.before(7.0) == 0.1
    ramp = TableSource(np.array([0.0, 2.0]), np.array([1.0, 3.0]))
    assert ramp.after(0.5) == ramp.before(0.5) == 1.5
    assert ramp.chord(0.5, 0.25) == (1.5, 0.25)  # 1.5 + 0.25 tau over [0.5, 0.75]
    assert ROAD.chord(0.05, 0.05) == (0.0, 0.0) and ROAD.chord(0.1, 0.05) == (0.1, 0.0)


def load(tmp_path, sources):
    (tmp_path / "road.csv").write_text("time,road,other\n0,0\n")
    (tmp_path / "one.csv").write_text("time,road\n0,0\n0.1,0\n0.1,0.1\n5,0.1\n")
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({**BASE, "sources": sources}))
    return load_scene(path)


def test_a_csv_table_and_a_constant_are_read(tmp_path):
    scene = load(tmp_path, [{"to": "b.z", "table": "one.csv"}, {"to": "a.u", "value": 2.5}])
    (u1, v1, road), (u2, v2, constant) = scene.sources
    assert (u1, v1, u2, v2) == ("b", "z", "a", "u")
    np.testing.assert_array_equal(road.times, ROAD.times)
    np.testing.assert_array_equal(road.values, ROAD.values)
    assert constant.after(0.3) == constant.before(0.3) == 2.5


@pytest.mark.parametrize("sources, where, says", [
    ({"to": "b.z"}, "sources", "must be a list"),
    ([{"to": "b.u", "value": 1.0}], "sources[0].to", "fed already by connections[0]"),
    ([{"to": "c.z", "value": 1.0}], "sources[0].to", "with a subsystem of a, b"),
    ([{"to": "b.z", "value": 1.0}, {"to": "b.z", "value": 2.0}], "sources[1].to", "fed already by sources[0]"),
    ([{"to": "b.z"}], "sources[0]", "takes one of table"),
    ([{"to": "b.z", "value": 1.0, "table": "one.csv"}], "sources[0]", "takes one of table"),
    ([{"to": "b.z", "value": True}], "sources[0].value", "finite number"),
    ([{"to": "b.z", "value": 1.0, "gain": 2}], "sources[0].gain", "allowed: to, table, column, value"),
    ([{"to": "b.z", "table": "none.csv"}], "sources[0].table", "is not a file"),
    ([{"to": "b.z", "table": "road.csv"}], "sources[0].column", "name one"),
    ([{"to": "b.z", "table": "road.csv", "column": "speed"}], "sources[0].column", "allowed: road, other"),
    ([{"to": "b.z", "table": "road.csv", "column": "other"}], "sources[0].table", "line 2"),
    ([{"to": "b.z", "table": {"time": [1, 0], "values": [0, 1]}}], "sources[0].table", "must not fall"),
    ([{"to": "b.z", "table": {"time": [0, 0, 0], "values": [0, 1, 2]}}], "sources[0].table", "three rows"),
    ([{"to": "b.z", "table": {"time": [0], "values": [0, 1]}}], "sources[0].table", "equal, non-zero length"),
    ([{"to": "b.z", "table": {"time": [0], "values": [0]}, "column": "x"}], "sources[0].column", "CSV file"),
])  # fmt: skip
def test_bad_sources_are_refused_naming_the_key(tmp_path, sources, where, says):
    with pytest.raises(SceneError) as refused:
        load(tmp_path, sources)
    assert f"scene.yaml: {where}:" in str(refused.value) and says in str(refused.value), str(refused.value)
