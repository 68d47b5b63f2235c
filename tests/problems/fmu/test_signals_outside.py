"""Signal connections between units other tools wrote: OMSimulator's DualMassOscillator coupled as its own test
couples it (tests/DualMassOscillator1.py in ../shared/outside/omsimulator: ``system1.F <- system2.F``,
``system2.{x1, v1, a1} <- system1.{x1, v1, a1}``, by the model descriptions' causalities; x1_start 0, x2_start
0.5), explicitly by the one macro step.

What the tests compare follows from the methods, not from numbers of the code under test:

* explicit Jacobi with held inputs is libcosim's fixed-step algorithm (every unit stepped once per macro step with
  the outputs of the point before, the inputs set from the outputs at the start), so on the same Co-Simulation
  units the two runs agree to rounding.  Not bit for bit: libcosim counts time in nanoseconds and hands a unit
  ``t_n = n ns / 1e9`` and the step ``t_n+1 - t_n``, icosim ``t_0 + n H`` and ``H``; these units' Euler steps
  follow those roundings (with libcosim's time points icosim's run is libcosim's bit for bit), and a last-bit
  difference per step is carried along: at most ``N eps`` of the amplitude after ``N`` steps;
* OMSimulator's published result of its test is explicit Jacobi with the inputs extrapolated at first order: it
  sets the units' input derivatives, the slope from the source units' output derivatives
  (``fmi2GetRealOutputDerivatives``; these units declare ``maxOutputDerivativeOrder`` 1) where icosim's ``k = 1``
  runs through the last two samples, a slope that differs by ``O(H)``: the two agree to a small part of the
  coupling error, not to rounding;
* on the Model Exchange units (integrated by icosim far below the coupling's error) the error against the exact
  solution of the linear Modelica equations (test_drives.exact) is of order ``k + 1`` with inputs extrapolated by
  the Lagrange polynomial of order ``k``, Jacobi and Gauss-Seidel alike (from the exact coupling history).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from test_drives import AMPLITUDE, C1, C2, K1, K2, M1, exact
from test_peers import OMSIMULATOR_CS, TRUCK, dmo_osp, dmo_ssp, truck_osp
from toolchains import OUTSIDE

from icosim.engine.run import simulate
from icosim.order_fit import asymptotic_order
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.exchange import open_fmu_unit
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import run_signal_scene
from icosim.problems.fmu.signals import SignalCosimulation, connections_of
from icosim.studies.peers.runners import DMO_UNITS, libcosim_dmo, libcosim_truck, quiet

pytestmark = pytest.mark.peers

OM = OUTSIDE / "omsimulator"
#: OMSimulator's four connections, as (source, output, target, input, factor, offset).
CONNECTIONS = [("system2", "F", "system1", "F", 1.0, 0.0)] + [
    ("system1", v, "system2", v, 1.0, 0.0) for v in ("x1", "v1", "a1")
]
EPS = np.finfo(float).eps


def dmo_scene(tmp_path, H, t_end, **coupling):
    data = {
        "subsystems": {
            "system1": {"fmu": str(OM / DMO_UNITS["system1"]), "start": {"x1_start": 0.0}},
            "system2": {"fmu": str(OM / DMO_UNITS["system2"]), "start": {"x2_start": 0.5}, "record": ["mass2.s"]},
        },
        "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u, _, _ in CONNECTIONS],
        "coupling": {"H": H, **coupling},
        "t_end": t_end,
    }
    path = tmp_path / f"dmo_{H:g}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_explicit_jacobi_with_held_inputs_gives_libcosim_numbers(tmp_path):
    H, t_end = 1e-4, 2.0
    run = run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end)))
    with quiet():
        peer = libcosim_dmo(dmo_osp(tmp_path / "lc", H), t_end)
    assert run.status == "completed" and abs(run.times[-1] - t_end) < 1e-12 and abs(peer["t"] - t_end) < 1e-12
    ours = run.series["system1.x1"][-1], run.series["system2.mass2.s"][-1]
    error = abs(ours[0] - exact([t_end])[0, 0])  # the coupling's first-order error, for scale
    n = round(t_end / H)
    for a, b in zip(ours, (peer["x1"], peer["x2"])):
        assert abs(a - b) <= n * EPS * AMPLITUDE < 1e-6 * error, (ours, peer)
    assert run.series["system1.F"][-1] == run.series["system2.F"][-1]  # the input is its connection's value
    assert len(run.series["system2.a1"]) == n + 1


def test_omsimulator_extrapolates_its_inputs_at_first_order(tmp_path):
    """OMSimulator hands these units (``canInterpolateInputs``) the inputs' first derivatives: its published x1(10),
    x2(10) at 1e-4 (its test's Result) are explicit Jacobi with k = 1 at the same step, far closer to icosim's run
    than either is to the exact solution (the coupling's error)."""
    H, t_end = 1e-4, 10.0
    run = run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=1)))
    ours = np.array([run.series["system1.x1"][-1], run.series["system2.mass2.s"][-1]])
    error = np.max(np.abs(ours - exact([t_end])[0, :2]))
    assert np.max(np.abs(ours - OMSIMULATOR_CS)) < 1e-3 * error, (ours, OMSIMULATOR_CS, error)


def exact_history(k, H):
    """The connections' values (F, x1, v1, a1) at ``0, -H, ... -kH`` from the exact solution."""
    rows = []
    for j in range(k + 1):
        x1, x2, v1, v2 = exact([-j * H])[0]
        force = K2 * (x2 - x1) + C2 * (v2 - v1)
        a1 = (force - K1 * x1 - C1 * v1) / M1
        rows.append([force, x1, v1, a1])
    return np.array(rows)


def model_exchange_error(k, H, t_end, scheme, implicit=False):
    """The run's largest position error at ``t_end`` on the Model Exchange units from the exact coupling history
    (engine directly), and the problem's record of its implicit coupling's work."""
    names = ["system1", "system2"]
    cons, inputs, outputs = connections_of(CONNECTIONS, names)
    starts = {"system1": {"x1_start": 0.0}, "system2": {"x2_start": 0.5}}
    units = [
        open_fmu_unit(
            n,
            OM / DMO_UNITS[n],
            {"signal_input": inputs[i], "signal_output": outputs[i]},
            starts[n],
            interface="model-exchange",
            tolerance=1e-12,
        )  # fmt: skip
        for i, n in enumerate(names)
    ]
    try:
        problem = SignalCosimulation(units, inputs, outputs, cons, k, H, implicit=implicit)
        history = problem.initial_history(exact_history(k, H))
        newton = {"iterations": 10, "tol": 1e-10} if implicit else {}
        traj = simulate(problem, None, problem.initial_state(), history, round(t_end / H), scheme=scheme,
                        record=False, **newton)  # fmt: skip
        assert traj.failed_at is None, traj.reason
        x = [units[0].get(("signal_output",)).ravel()[0], units[1].get_named("mass2.s")]
    finally:
        for unit in units:
            unit.close()
    return np.max(np.abs(np.array(x) - exact([t_end])[0, :2])), problem.implicit_work


@pytest.mark.parametrize("k, scheme", [(0, "jacobi"), (1, "jacobi"), (2, "jacobi"), (0, "gauss-seidel-12"),
                                       (1, "gauss-seidel-21")])  # fmt: skip
def test_extrapolation_of_order_k_gives_error_of_order_k_plus_one(k, scheme):
    Hs = [4e-3, 2e-3, 1e-3]
    errors = [model_exchange_error(k, H, 1.0, scheme)[0] for H in Hs]
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - (k + 1)) < 0.2, (errors, fit)


def feedthrough_loop_scene(tmp_path):
    """Two of the Reference-FMUs' Feedthrough, each fed by the other: a scene file of an algebraic loop."""
    fmu = OUTSIDE / "reference-fmus" / "fmus2" / "Feedthrough.fmu"
    data = {
        "subsystems": {"a": {"fmu": str(fmu)}, "b": {"fmu": str(fmu)}},
        "connections": [
            {"from": "a.Float64_continuous_output", "to": "b.Float64_continuous_input"},
            {"from": "b.Float64_continuous_output", "to": "a.Float64_continuous_input"},
        ],  # fmt: skip
        "coupling": {"H": 0.1},
        "t_end": 1.0,
    }
    path = tmp_path / "loop.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_loop_of_direct_feedthrough_is_refused_naming_it(tmp_path):
    """The Reference-FMUs' Feedthrough passes its input to its output without a step: two of them fed by each
    other form an algebraic loop of gain 1 (``I - J`` singular), refused as ill-posed before the first step."""
    path = feedthrough_loop_scene(tmp_path)
    with pytest.raises(SceneError, match=r"algebraic loop .*a\.Float64_continuous_output -> b\.Float64_continuous_"
                       r"input, b\.Float64_continuous_output -> a\.Float64_continuous_input is ill-posed"):  # fmt: skip
        run_signal_scene(load_scene(path))


def test_an_osp_file_of_signal_connections_runs_as_libcosim_runs_it(tmp_path):
    """The same OspSystemStructure.xml for both masters (fixed step 1e-3, no stop time: icosim's default 1 s);
    the file's System2 has no connector for mass2.s, so x1 is compared."""
    folder = dmo_osp(tmp_path / "osp", 1e-3)
    scene = load_scene(folder)
    assert scene.coupling["k"] == 0 and scene.scheme.name == "jacobi" and scene.t_end == 1.0
    run = run_signal_scene(scene)
    with quiet():
        peer = libcosim_dmo(folder, 1.0)
    assert abs(run.series["system1.x1"][-1] - peer["x1"]) <= 1000 * EPS * AMPLITUDE, (
        run.series["system1.x1"][-1],
        peer,
    )


def test_the_quarter_truck_s_own_file_coupled_by_signals_gives_libcosim_s_fixed_step_numbers(tmp_path):
    """OSP's quarter truck from its own OspSystemStructure.xml (its power bond's two connections), named by a scene
    whose coupling has no method: the bond coupled as signals, explicit Jacobi with held inputs at the file's base
    step, is libcosim's fixed-step algorithm; libcosim runs the same file with fixedStep for its ecco."""
    scene = tmp_path / "truck.yaml"
    scene.write_text(yaml.safe_dump({"system": str(TRUCK / "OspSystemStructure.xml"),
                                     "subsystems": {"chassis": {"record": ["position"]}},
                                     "coupling": {"H": 1e-4, "k": 0, "scheme": "jacobi", "implicit": False},
                                     "t_end": 1.0}))  # fmt: skip
    run = run_signal_scene(load_scene(scene))
    assert run.status == "completed" and run.times[-1] == pytest.approx(1.0)
    x = np.asarray(run.series["chassis.position"])
    with quiet():
        peer = libcosim_truck(truck_osp(tmp_path / "libcosim", 1e-4), 1.0)
    assert abs(x[-1] - peer["x"]) <= 1e-6 * np.max(np.abs(x)), (x[-1], peer)


def test_an_ssp_archive_of_signal_connections_records_its_other_connectors(tmp_path):
    """test_peers' SSP of the DualMassOscillator (System2's ``mass2.s`` an unconnected output connector), named by a
    scene that gives the step: the same run as libcosim's at that step."""
    ssp = dmo_ssp(tmp_path / "DualMassOscillator.ssp")
    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump({"system": str(ssp), "coupling": {"H": 1e-3}, "t_end": 1.0}))
    run = run_signal_scene(load_scene(scene))
    with quiet():
        peer = libcosim_dmo(dmo_osp(tmp_path / "lc", 1e-3), 1.0)
    ours = run.series["system1.x1"][-1], run.series["system2.mass2.s"][-1]
    for a, b in zip(ours, (peer["x1"], peer["x2"])):
        assert abs(a - b) <= 1000 * EPS * AMPLITUDE, (ours, peer)
