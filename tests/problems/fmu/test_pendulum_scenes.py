"""The double pendulum of Sect. 4 on two FMU units (fmus/pendulum_link1, fmus/pendulum_link2; the joint a point
in the plane, two components per coupling variable): the same joint trajectory and joint force as the built-in
pendulum (icosim.problems.pendulum.problem, Radau IIA at tolerance 1e-10) through the same macro step."""

import numpy as np
import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.engine.macrostep import macro_step
from icosim.engine.methods import make_method
from icosim.engine.run import simulate
from icosim.problems.fmu.problem import FmuCosimulation
from icosim.problems.fmu.run import open_units
from icosim.problems.fmu.scene import load_scene
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.problem import PendulumCosimulation
from icosim.problems.pendulum.reference import consistent_history

pytestmark = pytest.mark.fmu

SCENE = ROOT / "config" / "scenes" / "double_pendulum_ff.yaml"
SCENES = {"ff": SCENE, "fd": ROOT / "config" / "scenes" / "double_pendulum_fd.yaml"}
PARAMS = {"baumgarte": {"index": 1, "mu": 2e-3}, "weighted": {"index": 1, "a": 1.0, "b": 1.0}}


def write(tmp_path, decomposition="ff", **coupling):
    scene = SCENES[decomposition]
    data = yaml.safe_load(scene.read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str((scene.parent / sub["fmu"]).resolve())
    if "method" in coupling:
        data["coupling"] = {k: v for k, v in data["coupling"].items() if k not in ("index", "mu", "a", "b")}
        data["coupling"] |= PARAMS[coupling["method"]]
    data["coupling"] |= coupling
    path = tmp_path / "pendulum.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("decomposition", SCENES)
def test_the_examples_match_the_builtin_defaults(decomposition):
    """The scenes' start values are PendulumParameters' defaults and its consistent start."""
    p = PendulumParameters()
    data = yaml.safe_load(SCENES[decomposition].read_text())
    link1, link2 = data["subsystems"]["link1"]["start"], data["subsystems"]["link2"]["start"]
    assert (link1["m"], link1["l"], link1["J"], link1["g"], link1["d"], link1["phi0"]) == (
        p.m1, p.l1, p.J1, p.g, p.d, p.phi1_0
    )  # fmt: skip
    s0 = p.initial_state()
    assert (link2["x0"], link2["y0"], link2["phi0"]) == (s0[2], s0[3], p.phi2_0)
    H = data["coupling"]["H"]
    np.testing.assert_array_equal(data["initial_coupling"], consistent_history(p, decomposition, 0, H)[0])


STABLE = [
    ("baumgarte", 0, "jacobi"),
    ("baumgarte", 1, "jacobi"),
    ("baumgarte", 2, "jacobi"),
    ("baumgarte", 0, "gauss-seidel-12"),
    ("baumgarte", 0, "gauss-seidel-21"),
    ("weighted", 0, "jacobi"),
    ("weighted", 1, "jacobi"),
    ("weighted", 0, "gauss-seidel-12"),
]


@pytest.mark.parametrize("decomposition", SCENES)
@pytest.mark.parametrize("method, k, scheme", STABLE)
def test_fmu_pendulum_follows_the_builtin_pendulum(tmp_path, decomposition, method, k, scheme):
    """Stable configurations at H = 2 ms over 100 macro steps: joint points within 1e-9 m, the joint force
    within 1e-6 relative (the Gauss-Seidel schemes at k >= 1 are unstable here for both).  fd: link 2's joint
    point driven kinematically by link 1's acceleration (fmus/pendulum_link2_kinematic)."""
    n = 100
    scene = load_scene(write(tmp_path, decomposition, method=method, k=k, scheme=scheme))
    H = scene.coupling["H"]
    p = PendulumParameters()
    units, couplings = open_units(scene)
    try:
        problem = FmuCosimulation(units, couplings, decomposition, k, H)
        state, history = problem.initial_state(), consistent_history(p, decomposition, k, H)
        ys = []
        for _ in range(n):
            state, history, y = macro_step(problem, scene.method, state, history, scheme=scheme)
            ys.append(y)
        problem.close()
    finally:
        for unit in units:
            unit.close()
    builtin = PendulumCosimulation(p, decomposition, k, H, rtol=1e-10, atol=1e-10)
    method_ = make_method(method, **PARAMS[method])
    history = consistent_history(p, decomposition, k, H)
    traj = simulate(builtin, method_, p.initial_state(), history, n, scheme=scheme)
    assert traj.diverged_at is None and traj.failed_at is None
    ref, got = np.array(traj.outputs[1:]), np.array(ys)
    got[:, 1, 3, :] *= -1  # the units' forces are in the graph's sense, which acts with -lambda on the second
    assert np.max(np.abs(got[:, :, 0, :] - ref[:, :, 0, :])) < 1e-9
    force = np.max(np.abs(got[:, :, 3, :] - ref[:, :, 3, :])) / np.max(np.abs(ref[:, :, 3, :]))
    assert force < 1e-6


def test_a_planar_joint_needs_as_many_components_everywhere(capsys, tmp_path):
    data = yaml.safe_load(write(tmp_path).read_text())
    data["subsystems"]["link2"]["velocity"] = "Vx"
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["cosim", str(path), "--out", str(tmp_path / "run.nc")]) == 2
    err = capsys.readouterr().err
    assert "subsystems" in err and "as many components" in err and "link2.velocity: 1" in err


def test_projection_is_refused_for_a_planar_joint(capsys, tmp_path):
    path = write(tmp_path)
    data = yaml.safe_load(path.read_text())
    data["coupling"] = {"method": "projection", "decomposition": "ff", "k": 1, "H": 2e-3}
    for sub in data["subsystems"].values():
        sub |= {"mass": 1.0, "set_position": ["Px", "Py"], "set_velocity": ["Vx", "Vy"]}
    path.write_text(yaml.safe_dump(data))
    assert main(["cosim", str(path), "--out", str(tmp_path / "run.nc")]) == 2
    assert "projection moves one position per unit" in capsys.readouterr().err
