"""Model Exchange units (icosim.problems.fmu.exchange), on units of other tools (../shared/outside):

* OMSimulator's ``DualMassOscillator.System1`` (OpenModelica 1.24; its co-simulation cannot roll back) as Model
  Exchange, force driven, joined fd to the kinematically driven unit of fmus/ (``msd_kinematic``): the exact
  monolithic solution of the joined masses (from DualMassOscillator.mo's parameters and the fmus unit's start
  values, by scipy's ``expm``), with the convergence order of the method and ``k`` (Baumgarte index 1 at
  mu = 5e-3: O(H^(k+1)), config/claims/convergence.yaml);
* Model Exchange against Co-Simulation on the Modelica Reference-FMUs that have both: Dahlquist (x' = -k x, FMI
  2.0 and 3.0; its co-simulation steps with explicit Euler at the communication step) and StateSpace (FMI 3.0,
  driven through its input; its co-simulation integrates with explicit Euler at 1e-3 s), each against the exact
  solution;
* BouncingBall (an event indicator) refused as Model Exchange, naming the count; ``interface`` and ``tolerance``
  in the scene and the check table.
"""

import numpy as np
import pytest
import yaml
from helpers import FMU_CACHE, ROOT
from scipy.linalg import expm
from toolchains import OUTSIDE

from icosim.cli import main
from icosim.engine.run import simulate
from icosim.problems.fmu.build import build_unit
from icosim.problems.fmu.errors import FmuError
from icosim.problems.fmu.exchange import DEFAULT_TOLERANCE, ExchangeUnit, open_fmu_unit
from icosim.problems.fmu.problem import FmuCosimulation
from icosim.problems.fmu.run import open_units, run_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.units import Unit

pytestmark = [pytest.mark.outside, pytest.mark.fmu]

SYSTEM1 = OUTSIDE / "omsimulator" / "DualMassOscillator.System1.fmu"
REFERENCE = OUTSIDE / "reference-fmus"
# DualMassOscillator.mo, System1: m1, spring k1, damper c1
M1, K1, C1 = 1.0, 10.0, 0.2
# the kinematic unit of fmus/ (mass, spring, damper to the ground), chosen here
M2, K2, C2 = 2.0, 20.0, 0.5
X0 = 0.1


def joined(t):
    """The exact joined masses: (m1 + m2) x'' = -(k1 + k2) x - (c1 + c2) x', from x = X0 at rest; (x, v, a)."""
    A = np.array([[0.0, 1.0], [-(K1 + K2) / (M1 + M2), -(C1 + C2) / (M1 + M2)]])
    x, v = expm(A * t) @ [X0, 0.0]
    return x, v, (A @ [x, v])[1]


def msd_fmu():
    """fmus/msd, built: a co-simulation unit only."""
    return build_unit(ROOT / "fmus" / "msd", FMU_CACHE)


MSD_NAMES = {"position": "x", "velocity": "v", "acceleration": "a", "force": "lambda"}


def fd_scene(tmp_path, H, t_end, k, *, method="baumgarte", params=None, body1=None):
    body1 = {"fmu": str(SYSTEM1), "start": {"x1_start": X0}, "position": "x1", "velocity": "v1",
             "acceleration": "a1", "force": "F", "force_sign": 1} | (body1 or {})  # fmt: skip
    body2 = {"fmu": str(ROOT / "fmus" / "msd_kinematic"), "start": {"m": M2, "c": K2, "d": C2, "x0": X0},
             "position": "x", "velocity": "v", "acceleration": "a", "acceleration_input": "a_in",
             "reaction_force": "F", "force_sign": -1}  # fmt: skip
    params = {"index": 1, "mu": 5e-3} if params is None else params
    data = {"subsystems": {"body1": body1, "body2": body2}, "t_end": t_end,
            "coupling": {"method": method, "decomposition": "fd", "k": k, "H": H} | params}  # fmt: skip
    path = tmp_path / f"fd_{H:g}_{k}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def fd_error(tmp_path, H, t_end, k):
    """The largest position error of either body over the run, from the exact start (the coupling history at
    T_0 ... T_-k from the exact solution: lambda = m1 a + k1 x + c1 v on body1, and body1's acceleration)."""
    scene = load_scene(fd_scene(tmp_path, H, t_end, k))
    units, couplings = open_units(scene)
    problem = None
    try:
        assert isinstance(units[0], ExchangeUnit) and not isinstance(units[1], ExchangeUnit)
        history = []
        for j in range(k + 1):
            x, v, a = joined(-j * H)
            history.append([M1 * a + K1 * x + C1 * v, a])
        problem = FmuCosimulation(units, couplings, "fd", k, H)
        traj = simulate(problem, scene.method, problem.initial_state(), np.array(history), scene.n_steps)
        assert traj.failed_at is None
        x = np.array(traj.states)[..., 0]
        exact = np.array([joined(n * H)[0] for n in range(scene.n_steps + 1)])
        return float(np.max(np.abs(x - exact[:, None])))
    finally:
        if problem is not None:
            problem.close()
        for unit in units:
            unit.close()


@pytest.mark.parametrize("k, bound", [(0, 1e-3), (1, 1e-6), (2, 1e-8)])
def test_system1_as_model_exchange_follows_the_exact_joined_masses(tmp_path, k, bound):
    """Order k + 1 (Baumgarte index 1, mu = 5e-3), and at H = 1e-3 an error below ``bound`` of the amplitude."""
    Hs = [4e-3, 2e-3, 1e-3]
    errors = [fd_error(tmp_path, H, 0.4, k) for H in Hs]
    orders = np.diff(np.log(errors)) / np.diff(np.log(Hs))
    assert orders == pytest.approx([k + 1, k + 1], abs=0.1)
    assert errors[-1] < bound * X0


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12", "gauss-seidel-21"])
@pytest.mark.parametrize("k", [0, 1, 2])
@pytest.mark.parametrize("method, params", [("baumgarte", {"index": 1, "mu": 1e-3}),
                                            ("weighted", {"index": 1, "a": 1.0, "b": 1.0})])  # fmt: skip
def test_system1_as_model_exchange_follows_the_builtin_model(tmp_path, method, params, k, scheme):
    """The same scene as the built-in linear two-mass model with System1's parameters (icosim.problems.linear),
    every scheme: the same trajectory within 1e-9 of the largest value (the built-in model and the fmus unit
    integrate exactly, the model exchange unit to its tolerance; some of these configurations are unstable, from
    the start's inconsistency, as in tests/problems/fmu/test_linear_scenes.py)."""
    from icosim.engine.methods import engine_method, make_method
    from icosim.problems.linear.model import PhysicalModel
    from icosim.problems.linear.problem import LinearCosimulation

    H, n = 1e-3, 80
    path = fd_scene(tmp_path, H, n * H, k, method=method, params=params | {"scheme": scheme, "perturbation": 1.0})
    data = yaml.safe_load(path.read_text()) | {"initial_coupling": [0.0, 0.0], "divergence_bound": 1e300}
    path.write_text(yaml.safe_dump(data))
    run = run_scene(path)
    assert run.status == "completed" and run.units["body1"]["interface"] == "model-exchange"
    model = PhysicalModel(H=H, m1=M1, m2=M2, c1=K1, c2=K2, d1=C1, d2=C2)
    problem = LinearCosimulation(model.coefficients(), "fd", k)
    start, history = np.array([[X0, 0.0], [X0, 0.0]]), np.zeros((k + 1, problem.n_coupling))
    traj = simulate(problem, engine_method(make_method(method, **params), H), start, history, n, scheme=scheme)
    x = np.array(traj.states)[..., 0]
    assert np.max(np.abs(run.states[..., 0] - x)) < 1e-9 * max(1.0, np.max(np.abs(x)))


def test_interface_auto_takes_model_exchange_where_co_simulation_cannot_roll_back(tmp_path, capsys):
    path = fd_scene(tmp_path, 1e-3, 0.05, 1)
    run = run_scene(path)
    assert run.status == "completed"
    info = run.units["body1"]
    assert info["interface"] == "model-exchange" and run.units["body2"]["interface"] == "co-simulation"
    assert info["tolerance"] == DEFAULT_TOLERANCE and info["integrator"] == "scipy DOP853"
    assert info["continuous_states"] == 2 and info["rhs_evaluations"] > 0
    x = run.states[-1, :, 0]
    assert x == pytest.approx([joined(0.05)[0]] * 2, abs=1e-6 * X0)  # from the computed (held) start history
    assert main(["cosim", str(path), "--check"]) == 0
    text = capsys.readouterr().out
    assert "model exchange, integrated by icosim" in text
    assert "interface auto: its co-simulation cannot roll back (canGetAndSetFMUstate=false)" in text


def test_the_dataset_says_the_interface(tmp_path):
    path = fd_scene(tmp_path, 1e-3, 0.01, 0)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(path), "--out", str(out)]) == 0
    import xarray as xr

    with xr.open_dataset(out) as ds:
        assert ds.attrs["body1_interface"] == "model-exchange"
        assert ds.attrs["body2_interface"] == "co-simulation"


def test_tolerance_is_refused_on_a_co_simulation_unit(tmp_path, capsys):
    body = {"fmu": str(msd_fmu()), "interface": "co-simulation", "tolerance": 1e-8, "start": {}} | MSD_NAMES
    assert main(["cosim", str(fd_scene(tmp_path, 1e-3, 0.01, 0, body1=body)), "--out", str(tmp_path / "r.nc")]) == 2
    err = capsys.readouterr().err
    assert "body1: tolerance: is the integrator's tolerance of a model exchange unit" in err
    assert "(interface co-simulation)" in err and not (tmp_path / "r.nc").exists()
    with pytest.raises(FmuError, match="tolerance: .*coupled as co-simulation .*interface auto"):
        open_fmu_unit("msd", msd_fmu(), MSD_NAMES, {}, tolerance=1e-8)


def test_model_exchange_needs_the_interface():
    with pytest.raises(FmuError, match="interface: model-exchange: .* has no <ModelExchange>"):
        open_fmu_unit("msd", msd_fmu(), MSD_NAMES, {}, interface="model-exchange")


def test_the_projection_cannot_move_a_model_exchange_unit():
    names = {"position": "x1", "velocity": "v1", "acceleration": "a1", "force": "F", "set_position": "x1_start"}
    with pytest.raises(FmuError, match="set_position: a model exchange unit's state is its continuous states"):
        ExchangeUnit("body1", SYSTEM1, names, {})


def test_a_restored_step_repeats_bit_for_bit():
    names = {"position": "x1", "velocity": "v1", "acceleration": "a1", "force": "F"}
    unit = ExchangeUnit("body1", SYSTEM1, names, {"x1_start": X0})
    try:
        start = unit.save()
        unit.step("force", [[1.0], [0.5]], 0.0, 1e-2, step_index=1)
        first = unit.read(("position", "velocity", "acceleration"))
        unit.restore(start)
        assert unit.read(("position", "velocity")) == [X0, 0.0]
        unit.step("force", [[1.0], [0.5]], 0.0, 1e-2, step_index=1)
        assert unit.read(("position", "velocity", "acceleration")) == first
    finally:
        unit.close()


# -- Model Exchange against Co-Simulation: Reference-FMUs with both -------------------------------------------------


@pytest.mark.parametrize("version", ["fmus2", "fmus3"])
def test_dahlquist_model_exchange_is_exact_where_its_co_simulation_is_euler(version):
    """x' = -k x (k = 1, x(0) = 1) to t = 1: as Model Exchange exp(-1) to the integrator's tolerance at every H;
    its co-simulation steps with explicit Euler at its own fixed step of 0.1 s whatever the communication step,
    0.9^10 (5e-2 off)."""
    path = REFERENCE / version / "Dahlquist.fmu"
    for H, n in ((0.1, 10), (0.02, 50)):
        me = open_fmu_unit("d", path, {"position": "x"}, {}, interface="model-exchange")
        cs = open_fmu_unit("d", path, {"position": "x"}, {}, interface="co-simulation")
        try:
            assert me.interface == "model-exchange" and cs.interface == "co-simulation"
            for j in range(n):
                me.step(None, None, j * H, H, step_index=j + 1)
                cs._do_step(j * H, H, j + 1)
            x_me, x_cs = me.get(("position",))[0, 0], cs.get(("position",))[0, 0]
        finally:
            me.close()
            cs.close()
        assert x_me == pytest.approx(np.exp(-1.0), rel=1e-9)
        assert x_cs == pytest.approx(0.9**10, rel=1e-12)


def test_statespace_driven_through_its_input_as_model_exchange_and_co_simulation():
    """FMI 3.0 StateSpace (A = B = C = D = I, x(0) = 0): x1' = x1 + u1, y1 = x1 + u1, driven by u1(t) = a + b t
    as the coupling polynomial of each macro step; exact x1 = (a + b)(e^t - 1) - b t.  As Model Exchange to the
    integrator's tolerance; its co-simulation (explicit Euler at 1e-3 s inside) 3e-4 relative off."""
    a, b, H, n = 0.5, 2.0, 0.1, 10
    T = n * H
    exact = (a + b) * (np.exp(T) - 1.0) - b * T + a + b * T
    ys = {}
    for interface in ("model-exchange", "co-simulation"):
        unit = open_fmu_unit("ss", REFERENCE / "fmus3" / "StateSpace.fmu", {"position": "y[1]", "force": "u[1]"},
                             {}, interface=interface, substeps=10)  # fmt: skip
        try:
            for j in range(n):
                unit.step("force", [[a + b * j * H], [b * H]], j * H, H, step_index=j + 1)
            ys[interface] = unit.get(("position",))[0, 0]
        finally:
            unit.close()
    assert ys["model-exchange"] == pytest.approx(exact, rel=1e-9)
    assert 1e-5 < abs(ys["co-simulation"] / exact - 1.0) < 1e-3  # Euler's error at 1e-3 s, far above the tolerance


def test_a_unit_with_only_model_exchange_is_integrated(tmp_path):
    """Dahlquist (FMI 2.0) with its <CoSimulation> element taken out of the model description (the binary
    serves both): interface auto takes its model exchange."""
    import re
    import zipfile

    source, target = REFERENCE / "fmus2" / "Dahlquist.fmu", tmp_path / "Dahlquist.fmu"
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb"<CoSimulation.*?</CoSimulation>", b"", data, flags=re.S)
            zout.writestr(item, data)
    unit = open_fmu_unit("d", target, {"position": "x"}, {})
    try:
        assert isinstance(unit, ExchangeUnit) and unit.md.coSimulation is None
        assert "interface auto: it has no co-simulation" in unit.opened
        for j in range(10):
            unit.step(None, None, j * 0.1, 0.1, step_index=j + 1)
        assert unit.get(("position",))[0, 0] == pytest.approx(np.exp(-1.0), rel=1e-9)
    finally:
        unit.close()


# -- events --------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("version", ["fmus2", "fmus3"])
def test_bouncing_ball_is_refused_as_model_exchange_naming_its_event_indicators(version):
    path = REFERENCE / version / "BouncingBall.fmu"
    names = {"position": "h", "velocity": "v"}
    with pytest.raises(
        FmuError, match=r"ball: BouncingBall.fmu declares 1 event indicator \(numberOfEventIndicators=1\)"
    ):
        open_fmu_unit("ball", path, names, {}, interface="model-exchange")
    unit = open_fmu_unit("ball", path, names, {})  # auto: its co-simulation rolls back and handles the bounce
    try:
        assert isinstance(unit, Unit) and unit.interface == "co-simulation"
    finally:
        unit.close()


@pytest.mark.parametrize("version", ["fmus2", "fmus3"])
def test_a_time_event_is_refused_naming_its_time(version):
    """Stair counts up at every second: no event indicators, but a time event at t = 1 s."""
    with pytest.raises(FmuError, match=r"stair: declares a time event at t = 1 s .*use interface co-simulation"):
        open_fmu_unit("stair", REFERENCE / version / "Stair.fmu", {}, {}, interface="model-exchange")


def test_bouncing_ball_refusal_is_the_open_row_of_the_check(tmp_path, capsys):
    path = fd_scene(tmp_path, 1e-3, 0.01, 0, body1={"fmu": str(REFERENCE / "fmus2" / "BouncingBall.fmu"),
                    "interface": "model-exchange", "position": "h", "velocity": "v", "acceleration": "v",
                    "force": "g", "start": {}})  # fmt: skip
    assert main(["cosim", str(path), "--check"]) == 2
    text = capsys.readouterr().out
    assert "open          refused" in text and "declares 1 event indicator" in text


def test_system1_as_co_simulation_is_refused_pointing_to_model_exchange():
    names = {"position": "x1", "velocity": "v1", "acceleration": "a1", "force": "F"}
    with pytest.raises(FmuError, match="canGetAndSetFMUstate=false; .*use interface: model-exchange"):
        open_fmu_unit("body1", SYSTEM1, names, {}, interface="co-simulation")
