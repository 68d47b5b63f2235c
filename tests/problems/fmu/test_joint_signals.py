"""Joints beside signal connections in one scene, coupled explicitly or implicitly: two units joined by a rigid joint
and a third fed by a connection from one of them (and, with the Reference-FMUs' StateSpace as a joint unit, feeding
it back).

Checked against the same system as one linear ODE solved by the matrix exponential (the joint eliminated: the two
joined masses move as one), the error converging with H at the order of the inputs' extrapolation, ``k + 1``; the
joint units' run is the scene of joints alone where no connection feeds back; the dataset holds both kinds of
output; bad input is refused naming the key.
"""

import numpy as np
import pytest
import yaml
from helpers import ROOT
from scipy.linalg import expm
from toolchains import OUTSIDE

from icosim.cli import main
from icosim.io.netcdf import open_dataset
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.joint_signal_run import run_joint_signal_scene
from icosim.problems.fmu.run import run_scene
from icosim.problems.fmu.scene import load_scene

pytestmark = pytest.mark.fmu

MSD = str(ROOT / "fmus" / "msd")
STATESPACE = OUTSIDE / "reference-fmus" / "fmus3" / "StateSpace.fmu"
#: the joined units (m, c, d), the third one's, the connection's gain into it (N/m) and back (N/m)
M1, M2, M3 = (1.0, 1000.0, 2.0), (2.0, 500.0, 1.0), (0.5, 800.0, 1.0)
K, G = 200.0, -300.0
T = 0.2


def msd(params, x0, joint=True):
    m, c, d = params
    sub = {"fmu": MSD, "start": {"m": m, "c": c, "d": d, "x0": x0}}
    if not joint:
        return sub | {"record": ["x"]}
    return sub | {"position": "x", "velocity": "v", "acceleration": "a", "force": "lambda", "force_sign": 1,
                  "mass": "m", "set_position": "x_set", "set_velocity": "v_set"}  # fmt: skip


def statespace(params):
    """The Reference-FMUs' StateSpace (FMI 3.0, three states, x0 ignored: it starts at rest) as a mass in its first
    two states, model exchange: u[1] the joint's force, u[2] a connection's force."""
    m, c, d = params
    a, b = [-c / m, -d / m, 0.0], [1 / m, 1 / m, 0.0]
    return {"fmu": str(STATESPACE), "interface": "model-exchange",
            "start": {"A": [[0.0, 1.0, 0.0], a, [0.0] * 3], "B": [[0.0] * 3, b, [0.0] * 3],
                      "C": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], a], "D": [[0.0] * 3, [0.0] * 3, b], "u": [0.0] * 3},
            "position": "y[1]", "velocity": "y[2]", "acceleration": "y[3]", "force": "u[1]", "force_sign": 1}  # fmt: skip


def write(tmp_path, subsystems, connections, k, H, scheme="jacobi", method="projection", implicit=False):
    coupling = {"method": method, "k": k, "H": H} | ({"index": 1, "mu": 1e-3} if method == "baumgarte" else {})
    coupling |= {"implicit": True} if implicit else {}
    coupling |= {"scheme": scheme} if isinstance(scheme, str) else {"scheme": "gauss-seidel", "order": scheme}
    data = {"subsystems": subsystems, "joints": [{"between": ["body1", "body2"], "decomposition": "ff"}],
            "connections": connections, "coupling": coupling, "t_end": T}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def one_way(tmp_path, k, H, scheme="jacobi", implicit=False):
    """body1 and body2 joined at x = 0.1 m, the sensor at rest pulled by K x1."""
    subs = {"body1": msd(M1, 0.1), "body2": msd(M2, 0.1), "sensor": msd(M3, 0.0, joint=False)}
    cons = [{"from": "body1.x", "to": "sensor.lambda", "factor": K}]
    return write(tmp_path, subs, cons, k, H, scheme, implicit=implicit)


def exact(x0, g=0.0):
    """``(x, v, x3, v3)`` at ``T``: the joined masses ``(m1 + m2) x'' = -(c1 + c2) x - (d1 + d2) x' + g x3`` and the
    sensor ``m3 x3'' = -c3 x3 - d3 x3' + K x``, from ``x0``."""
    m, c, d = (a + b for a, b in zip(M1, M2))
    m3, c3, d3 = M3
    A = np.array([[0, 1, 0, 0], [-c / m, -d / m, g / m, 0], [0, 0, 0, 1], [K / m3, 0, -c3 / m3, -d3 / m3]])
    return expm(A * T) @ np.asarray(x0, dtype=float)


def slopes(errors, Hs):
    return np.log2(np.asarray(errors[:-1]) / np.asarray(errors[1:])) / np.log2(np.asarray(Hs[:-1]) / Hs[1:])


@pytest.mark.parametrize("k", [0, 1, 2])
def test_the_sensor_converges_at_the_order_of_its_input(tmp_path, k):
    """Jacobi, the sensor's input held (k = 0) or extrapolated: its position's error at T falls as H^(k+1); the
    joined masses' (projection) are far below it (the sensor does not act on them)."""
    Hs = np.array([1e-3, 5e-4, 2.5e-4])
    z = exact([0.1, 0.0, 0.0, 0.0])
    errors = []
    for H in Hs:
        run = run_joint_signal_scene(load_scene(one_way(tmp_path, k, float(H))))
        assert run.status == "completed"
        errors.append(abs(run.signals.series["sensor.x"][-1] - z[2]))
        assert abs(run.joints.positions[-1, 0, 0] - z[0]) < errors[-1]
        assert np.array_equal(run.joints.positions[:, 0], run.joints.positions[:, 1])  # projected onto the joint
    assert np.all(np.abs(slopes(errors, Hs)[-1:] - (k + 1)) < 0.3), errors


@pytest.mark.parametrize("scheme", ["jacobi", ["body1", "sensor", "body2"]])
def test_the_joints_run_as_the_scene_of_joints_alone(tmp_path, scheme):
    """The sensor does not act on the joined masses: their positions, velocities, outputs and coupling variables are
    those of the scene without it, bit for bit (Jacobi; Gauss-Seidel with the sensor between them)."""
    path = one_way(tmp_path, 1, 1e-3, scheme)
    both = run_joint_signal_scene(load_scene(path))
    data = yaml.safe_load(path.read_text())
    del data["connections"], data["subsystems"]["sensor"]
    if "order" in data["coupling"]:
        data["coupling"]["order"].remove("sensor")
    alone = tmp_path / "joints.yaml"
    alone.write_text(yaml.safe_dump(data))
    joints = run_scene(load_scene(alone))
    for what in ("states", "coupling"):
        assert np.array_equal(getattr(both.joints, what), getattr(joints, what)), what
    assert np.array_equal(both.joints.outputs[1:], joints.outputs[1:])
    # the connection's value is K times body1's position as its corrector left it, at every point
    x1 = np.concatenate([[0.1], joints.outputs[1:, 0, 0, 0]])
    assert np.allclose(both.signals.series["sensor.lambda"], K * x1, rtol=1e-15, atol=0)


@pytest.mark.parametrize("k", [0, 1])
def test_implicitly_the_sensor_converges_and_the_joints_run_as_alone(tmp_path, k):
    """Coupled implicitly, the sensor's error falls as H^(k+1); the joined masses, on which the connection does not
    act, move as in the scene of joints alone (their conditions closed in one Newton step, a linear problem)."""
    Hs = np.array([1e-3, 5e-4, 2.5e-4])
    z = exact([0.1, 0.0, 0.0, 0.0])
    errors = []
    for H in Hs:
        path = one_way(tmp_path, k, float(H), implicit=True)
        run = run_joint_signal_scene(load_scene(path))
        errors.append(abs(run.signals.series["sensor.x"][-1] - z[2]))
        assert max(run.signals.iterations) == 1  # one Newton step, then the test
        explicit = run_joint_signal_scene(load_scene(one_way(tmp_path, k, float(H))))
        assert np.allclose(run.joints.states, explicit.joints.states, rtol=1e-12, atol=1e-15)
    assert np.all(np.abs(slopes(errors, Hs)[-1:] - (k + 1)) < 0.3), errors


def test_the_dataset_holds_the_joints_and_the_connections(tmp_path, capsys):
    path = one_way(tmp_path, 1, 1e-3)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(path), "--out", str(out)]) == 0
    assert "sensor.lambda" in capsys.readouterr().out
    with open_dataset(out) as ds:
        assert list(ds["subsystem"].values) == ["body1", "body2"]
        assert {"position", "joint_force", "joint_gap", "coupling", "sensor.lambda", "body1.x", "sensor.x"} <= set(
            ds.variables
        )
        assert ds.attrs["coupling"] == "explicit" and ds.attrs["connections"] == 1
        assert yaml.safe_load(ds.attrs["scene_json"])["connections"][0]["to"] == "sensor.lambda"
        assert ds["time"].size == round(T / 1e-3) + 1 and ds["sensor.x"].size == ds["time"].size


def feedback(tmp_path, k, H, scheme="jacobi", implicit=False):
    """body1 (msd) joined to body2 (StateSpace), both at rest; the sensor starts at 0.05 m, pulled by K x1, and
    pushes body2 by G x3."""
    subs = {"body1": msd(M1, 0.0), "body2": statespace(M2), "sensor": msd(M3, 0.05, joint=False)}
    cons = [
        {"from": "body1.x", "to": "sensor.lambda", "factor": K},
        {"from": "sensor.x", "to": "body2.u[2]", "factor": G},
    ]
    return write(tmp_path, subs, cons, k, H, scheme, method="baumgarte", implicit=implicit)


def feedback_errors(tmp_path, k, scheme="jacobi", implicit=False, Hs=(1e-3, 5e-4, 2.5e-4)):
    """body1's and the sensor's position errors at T, a row per H."""
    z = exact([0.0, 0.0, 0.05, 0.0], G)
    errors = []
    for H in Hs:
        run = run_joint_signal_scene(load_scene(feedback(tmp_path, k, float(H), scheme, implicit)))
        assert run.status == "completed"
        errors.append([abs(run.joints.positions[-1, 0, 0] - z[0]), abs(run.signals.series["sensor.x"][-1] - z[2])])
    return np.array(errors)


@pytest.mark.outside
@pytest.mark.parametrize("k, scheme, implicit", [
    (0, "jacobi", False), (1, "jacobi", False), (0, ["sensor", "body1", "body2"], False),
    (0, "jacobi", True), (1, "jacobi", True), (2, "jacobi", True)])  # fmt: skip
def test_a_connection_into_a_joint_unit_converges_at_the_order_of_the_inputs(tmp_path, k, scheme, implicit):
    """The sensor's force on body2 (StateSpace's second input, handed with the joint's force in the same step) and
    body1's position into the sensor: both positions' errors at T fall as H^(k+1) (Baumgarte, index 1), explicitly
    and implicitly (the joint's and the connections' conditions closed by one corrector)."""
    Hs = np.array([1e-3, 5e-4, 2.5e-4])
    errors = feedback_errors(tmp_path, k, scheme, implicit, Hs)
    for column in errors.T:
        assert np.all(np.abs(slopes(column, Hs)[-1:] - (k + 1)) < 0.3), errors


@pytest.mark.outside
def test_implicitly_the_order_of_the_units_changes_only_newtons_start(tmp_path):
    """Gauss-Seidel's stages (the sensor first, its new sample into body2's step) move Newton's start, not the
    solution of the conditions at T_N+1: Jacobi's errors to within Newton's tolerance."""
    jacobi = feedback_errors(tmp_path, 1, implicit=True, Hs=(1e-3,))
    order = feedback_errors(tmp_path, 1, ["sensor", "body1", "body2"], implicit=True, Hs=(1e-3,))
    assert np.allclose(order, jacobi, rtol=1e-6, atol=0), (order, jacobi)


@pytest.mark.parametrize("change, where, says", [
    (lambda d: d["coupling"].update(tol=1e-9), "coupling.tol", "belongs to implicit: true"),
    (lambda d: d["coupling"].update(implicit=True, tol=0), "coupling.tol", "must be a number > 0"),
    (lambda d: d["coupling"].update(implicit="yes"), "coupling.implicit", "must be true or false"),
    (lambda d: d["connections"].append({"from": "sensor.x", "to": "body2.lambda"}), "connections[1].to",
     "body2.lambda is body2's force"),
    (lambda d: d["subsystems"]["sensor"].update(force_sign=1), "subsystems.sensor.force_sign",
     "not a key of a subsystem coupled by connections"),
    (lambda d: d["coupling"].update(scheme="gauss-seidel", order=["body1", "body2"]), "coupling.order",
     "every subsystem once"),
    (lambda d: d["coupling"].update(scheme="gauss-seidel-21"), "coupling.scheme", "the scene has 3"),
    (lambda d: d["subsystems"].update(idle=d["subsystems"]["sensor"]), "subsystems.idle",
     "takes part in no joint or connection"),
    (lambda d: d["coupling"].update(method="newton"), "coupling.method", "is not allowed"),
])  # fmt: skip
def test_bad_input_is_refused_naming_the_key(tmp_path, change, where, says):
    path = one_way(tmp_path, 0, 1e-3)
    data = yaml.safe_load(path.read_text())
    change(data)
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SceneError) as refused:
        load_scene(path)
    assert f"scene.yaml: {where}:" in str(refused.value) and says in str(refused.value), str(refused.value)


def test_predict_check_and_tolerance_are_refused_naming_why(tmp_path, capsys):
    path = one_way(tmp_path, 0, 1e-3)
    for flag in ("--predict", "--check"):
        assert main(["cosim", str(path), flag]) == 2
        assert f"joints beside connections, which {flag} does not serve" in capsys.readouterr().err
    assert main(["cosim", str(path), "--tolerance", "1e-6", "--out", str(tmp_path / "run.nc")]) == 2
    assert "argument --tolerance:" in capsys.readouterr().err


@pytest.mark.outside
def test_implicitly_a_unit_that_cannot_save_its_state_is_refused_before_any_unit_opens(tmp_path):
    """OpenModelica's DualMassOscillator.System1 as co-simulation (canGetAndSetFMUstate false) in the sensor's place:
    implicit coupling steps it again from T_N."""
    path = one_way(tmp_path, 0, 1e-3, implicit=True)
    data = yaml.safe_load(path.read_text())
    data["subsystems"]["sensor"] = {"fmu": str(OUTSIDE / "omsimulator" / "DualMassOscillator.System1.fmu"),
                                    "interface": "co-simulation"}  # fmt: skip
    data["connections"] = [{"from": "body1.x", "to": "sensor.F"}]
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SceneError, match=r"subsystems\.sensor: .*canGetAndSetFMUstate=false.*implicit: false"):
        run_joint_signal_scene(load_scene(path))
