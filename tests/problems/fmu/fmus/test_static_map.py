"""The unit fmus/static_map (y = a u + b + c sin(u) + q u^3, w = y, z = b) through fmpy's low-level API: its outputs
y and w follow its input at once, z does not move with it, its directional derivatives are those of the map, and
after a step its input holds its polynomial's value at the step end; each value computed by hand."""

import math

import pytest
from fmpy import read_model_description
from helpers import FMU_CACHE, ROOT, fmu_instance

from icosim.problems.fmu.build import build_unit

pytestmark = pytest.mark.fmu

A, B, C, Q, U, Y, Z, W, FAIL = range(9)  # value references


def test_the_outputs_follow_the_input_at_once_and_z_does_not(tmp_path):
    fmu = fmu_instance("static_map", tmp_path / "static_map")
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([A, B, C, Q], [0.5, 0.2, 2.0, 0.1])
        fmu.exitInitializationMode()
        for u in (0.7, -1.3):
            fmu.setReal([U], [u])  # no step
            y = 0.5 * u + 0.2 + 2.0 * math.sin(u) + 0.1 * u**3
            assert fmu.getReal([Y, W, Z]) == pytest.approx([y, y, 0.2], rel=1e-15)
            dy = 0.5 + 2.0 * math.cos(u) + 0.3 * u**2  # its directional derivatives, by hand
            assert fmu.getDirectionalDerivative([Y, W, Z], [U], [2.0]) == pytest.approx([2 * dy, 2 * dy, 0], rel=1e-15)
        H = 0.5
        fmu.setRealInputDerivatives([U], [1], [2.0])
        fmu.doStep(0.0, H)
        assert fmu.getReal([U]) == [-1.3 + 2.0 * H]
    finally:
        fmu.freeInstance()


def test_its_structure_gives_y_its_dependency_and_leaves_z_and_w_to_be_measured():
    md = read_model_description(str(build_unit(ROOT / "fmus" / "static_map", FMU_CACHE)))
    deps = {o.variable.name: o.dependencies for o in md.outputs}
    assert [v.name for v in deps["y"]] == ["u"] and deps["z"] is None and deps["w"] is None
