"""``--predict`` on a signal scene: OMSimulator's DualMassOscillator coupled by its four signal connections
(tests/DualMassOscillator1.py in ../shared/outside/omsimulator; test_signals_outside's CONNECTIONS), and its
QuarterCarModel in both splits (tests/QuarterCarModel.py).

What the tests compare, and where the numbers come from:

* the identified units against the Modelica equations of DualMassOscillator.mo and QuarterCarModel.mo with their
  parameters (test_drives' M1, K1, ...): the transfer functions ``C (sI - A)^-1 B + D`` (which do not depend on the
  coordinates a unit picks for its states: System2's are its ground spring's ``sd3.s_rel = -x2``, ``sd3.v_rel``);
  the Co-Simulation units' one-step maps against explicit Euler at the communication step (their solver, by the
  outside README), ``z``-transfer functions of ``x_n+1 = (I + H A) x_n + H B u_n``;
* the predicted rho against the growth per macro step measured on the run itself (the largest ``|x1|`` in a late
  window against an earlier one), within 5 % of ``rho - 1`` (the growth exponent), at an H where explicit
  coupling is unstable; and a run at a stable H stays bounded.
"""

import numpy as np
import pytest
import yaml
from test_drives import C1, C2, C3, K1, K2, K3, M1, M2
from test_signals_outside import CONNECTIONS, OM, feedthrough_loop_scene
from toolchains import OUTSIDE

import icosim.problems.fmu.predict_signals as predict_signals
from icosim.cli import main
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.predict_signals import predict_signal_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import run_signal_scene

pytestmark = pytest.mark.outside

UNITS = {"system1": "DualMassOscillator.System1.fmu", "system2": "DualMassOscillator.System2.fmu"}
# DualMassOscillator.mo in the physical coordinates: System1 (x1, v1), input F, outputs x1, v1, a1;
# System2 (x2, v2), inputs x1, v1, a1, output F = k2 (x2 - x1) + c2 (v2 - v1), m2 a2 = -k3 x2 - c3 v2 - F
MODELICA = {
    "system1": (
        np.array([[0, 1], [-K1 / M1, -C1 / M1]]),
        np.array([[0], [1 / M1]]),
        np.array([[1, 0], [0, 1], [-K1 / M1, -C1 / M1]]),
        np.array([[0], [0], [1 / M1]]),
    ),
    "system2": (
        np.array([[0, 1], [-(K2 + K3) / M2, -(C2 + C3) / M2]]),
        np.array([[0, 0, 0], [K2 / M2, C2 / M2, 0]]),
        np.array([[K2, C2]]),
        np.array([[-K2, -C2, 0]]),
    ),
}


def scene(tmp_path, H, t_end, interface, **coupling):
    data = {
        "subsystems": {
            n: {"fmu": str(OM / f), "interface": interface, "start": {"x1_start": 0.0} if n == "system1" else {}}
            for n, f in UNITS.items()
        },
        "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u, _, _ in CONNECTIONS],
        "coupling": {"H": H, **coupling},
        "t_end": t_end,
    }
    data["subsystems"]["system2"]["start"] = {"x2_start": 0.5}
    path = tmp_path / f"dmo_{interface}_{H:g}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def transfer(A, B, C, D, s):
    return C @ np.linalg.solve(s * np.eye(len(A)) - A, B) + D


def growth(run, steps):
    """Growth per macro step: the largest |x1| over the last sixth of the run against that over the sixth at its
    middle, per step between them."""
    x = np.abs(np.asarray(run.series["system1.x1"]))
    w = steps // 6
    return (np.max(x[steps - w + 1 :]) / np.max(x[steps // 2 : steps // 2 + w])) ** (1 / (steps - w + 1 - steps // 2))


def test_model_exchange_units_are_identified_as_their_modelica_equations(tmp_path):
    answer = predict_signal_scene(load_scene(scene(tmp_path, 0.1, 1.0, "model-exchange")))
    for name, u in answer["units"].items():
        assert u["interface"] == "model-exchange" and u["misfit"] < 1e-9, u
        got = [np.array(u[key]) for key in "ABCD"]
        assert sorted(np.linalg.eigvals(got[0]).tolist(), key=np.imag) == pytest.approx(
            sorted(np.linalg.eigvals(MODELICA[name][0]).tolist(), key=np.imag), rel=1e-8
        )
        for s in (0.0, 1j, 5j, 20j, 2 + 3j):
            assert transfer(*got, s) == pytest.approx(transfer(*MODELICA[name], s), rel=1e-7, abs=1e-9), (name, s)
    assert answer["units"]["system2"]["states"] == ["sd3.s_rel", "sd3.v_rel"]


def test_co_simulation_units_are_identified_as_euler_steps_of_their_equations(tmp_path):
    H = 0.1
    answer = predict_signal_scene(load_scene(scene(tmp_path, H, 1.0, "co-simulation")))
    for name, u in answer["units"].items():
        assert u["interface"] == "co-simulation" and u["misfit"] < 1e-9, u
        A, B, C, D = MODELICA[name]
        euler = (np.eye(2) + H * A, H * B, C, D)
        got = [np.array(u[key]) for key in "ABCD"]
        for z in (np.exp(0.3j), np.exp(2j), -1.0, 2.0):
            assert transfer(*got, z) == pytest.approx(transfer(*euler, z), rel=1e-7, abs=1e-9), (name, z)


def euler_jacobi_radius(H):
    """rho of explicit Jacobi with held inputs on the Modelica equations stepped by explicit Euler at H, in the
    block form of the recurrence on ``(x_1, x_2, e)``: ``x_i' = Phi_i x_i + Gamma_i E_i e``, ``e' = S y'`` with
    ``y_i' = C_i x_i' + D_i E_i e`` (``E_i`` picks unit i's inputs of e, ``S`` the connections' sources of y)."""
    names = list(UNITS)
    inputs = {n: [u for a, y, b, u, _, _ in CONNECTIONS if b == n] for n in names}
    outputs = {"system1": ["x1", "v1", "a1"], "system2": ["F"]}  # MODELICA's order
    cols = [f"{b}.{u}" for a, y, b, u, _, _ in CONNECTIONS]
    rows = [f"{a}.{y}" for a, y, b, u, _, _ in CONNECTIONS]
    ys = [f"{n}.{y}" for n in names for y in outputs[n]]
    S = np.array([[1.0 if r == y else 0.0 for y in ys] for r in rows])
    blocks = []
    for n in names:
        A, B, C, D = MODELICA[n]
        E = np.array([[1.0 if c == f"{n}.{u}" else 0.0 for c in cols] for u in inputs[n]])
        blocks.append((np.eye(2) + H * A, H * B @ E, C, D @ E))
    Phi = np.block([[blocks[0][0], np.zeros((2, 2))], [np.zeros((2, 2)), blocks[1][0]]])
    G = np.vstack([blocks[0][1], blocks[1][1]])
    C = np.block([[blocks[0][2], np.zeros((3, 2))], [np.zeros((1, 2)), blocks[1][2]]])
    D = np.vstack([blocks[0][3], blocks[1][3]])
    M = np.block([[Phi, G], [S @ C @ Phi, S @ (C @ G + D)]])
    return np.max(np.abs(np.linalg.eigvals(M)))


def test_the_largest_stable_step_of_co_simulation_units_is_that_of_their_euler_steps(tmp_path):
    """Their one-step maps identified anew at each step the search tries; against a bisection of the block-form
    rho of the Euler steps of the Modelica equations (euler_jacobi_radius); runs either side of it."""
    limit = predict_signal_scene(load_scene(scene(tmp_path, 0.01, 1.0, "co-simulation")))["largest_stable_H"]
    lo, hi = 1e-3, 0.1
    assert euler_jacobi_radius(lo) < 1 < euler_jacobi_radius(hi)
    while hi / lo > 1 + 1e-6:
        lo, hi = (np.sqrt(lo * hi), hi) if euler_jacobi_radius(np.sqrt(lo * hi)) < 1 else (lo, np.sqrt(lo * hi))
    assert limit["status"] == "bisected" and limit["identifications"] > 0
    assert limit["H_max"] <= hi and lo <= limit["H_unstable"] and limit["H_unstable"] / limit["H_max"] < 1.002
    for factor, grows in ((0.8, False), (1.25, True)):
        H = factor * limit["H_max"]
        steps = round(30.0 / H)
        x = np.abs(np.asarray(run_signal_scene(load_scene(scene(tmp_path, H, steps * H, "co-simulation"))).series[
            "system1.x1"]))  # fmt: skip
        assert (np.max(x[-steps // 4 :]) > np.max(x[: steps // 4])) == grows, (factor, H)


@pytest.mark.parametrize("coupling", [{"k": 0}, {"k": 0, "scheme": "gauss-seidel", "order": ["system1", "system2"]},
                                      {"k": 1, "scheme": "gauss-seidel", "order": ["system2", "system1"]}])  # fmt: skip
def test_an_unstable_run_grows_by_the_predicted_rho(tmp_path, coupling):
    H, steps = 0.2, 300
    path = scene(tmp_path, H, steps * H, "model-exchange", **coupling)
    answer = predict_signal_scene(load_scene(path))
    mine = next(row for row in answer["schemes"] if row["scene"])
    rho = mine["rho"]
    assert mine["verdict"] == "unstable" and rho > 1.01, mine
    run = run_signal_scene(load_scene(path))
    assert run.status == "completed"
    measured = growth(run, steps)
    assert abs(measured - rho) <= 0.05 * (rho - 1), (measured, rho)
    limit = answer["largest_stable_H"]
    assert limit["status"] == "bisected" and limit["H_max"] < H


def test_a_run_at_a_stable_step_stays_bounded(tmp_path):
    probe = predict_signal_scene(load_scene(scene(tmp_path, 0.2, 1.0, "model-exchange")))
    H = 0.5 * probe["largest_stable_H"]["H_max"]
    steps = round(20.0 / H)
    path = scene(tmp_path, H, steps * H, "model-exchange")
    answer = predict_signal_scene(load_scene(path))
    assert answer["schemes"][0]["verdict"] == "stable", answer["schemes"][0]
    run = run_signal_scene(load_scene(path))
    x = np.abs(np.asarray(run.series["system1.x1"]))
    assert run.status == "completed" and np.max(x[steps // 2 :]) < np.max(x[: steps // 2])


def test_co_simulation_growth_is_the_predicted_rho_and_k_1_is_undecided(tmp_path):
    H, steps = 0.1, 300
    path = scene(tmp_path, H, steps * H, "co-simulation")
    rho = predict_signal_scene(load_scene(path))["schemes"][0]["rho"]
    assert rho > 1.01
    measured = growth(run_signal_scene(load_scene(path)), steps)
    assert abs(measured - rho) <= 0.05 * (rho - 1), (measured, rho)
    answer = predict_signal_scene(load_scene(scene(tmp_path, H, 1.0, "co-simulation", k=1)))
    assert all(row["verdict"] == "undecided" and "k = 0 only" in row["reason"] for row in answer["schemes"])


def test_the_command_line_prints_the_prediction(tmp_path, capsys):
    assert main(["cosim", str(scene(tmp_path, 0.2, 1.0, "model-exchange")), "--predict"]) == 0
    out = capsys.readouterr().out
    assert "system2 identified (model-exchange" in out and "largest stable H of the scene's scheme" in out
    assert "* Jacobi" in out and "unstable" in out


# OMSimulator's QuarterCarModel.mo, split across the suspension (tests/QuarterCarModel.py): the chassis reads the
# wheel's position and velocity and the wheel the chassis's (displacement/displacement), or the wheel returns the
# suspension's force F = k_c (z_w - z_c) + d_c (v_w - v_c) (displacement/force); the road input z held at 0.1 m
M_W, M_C, K_W, K_C, D_C = 40.0, 400.0, 150e3, 15e3, 1e3
QUARTER_CAR = {
    "DisplacementDisplacement": [("Chassis", "z_c", "Wheel", "z_c"), ("Chassis", "der_z_c", "Wheel", "der_z_c"),
                                 ("Wheel", "z_w", "Chassis", "z_w"), ("Wheel", "der_z_w", "Chassis", "der_z_w")],
    "DisplacementForce": [("Wheel", "F", "Chassis", "F"), ("Chassis", "z_c", "Wheel", "z_c"),
                          ("Chassis", "der_z_c", "Wheel", "der_z_c")],
}  # fmt: skip
# the displacement/force split in (z, v): the chassis a free mass driven by F, the wheel on its tyre spring
QUARTER_CAR_DF = {
    "Chassis": (np.array([[0, 1], [0, 0]]), np.array([[0], [1 / M_C]]), np.eye(2), np.zeros((2, 1))),
    "Wheel": (
        np.array([[0, 1], [-(K_W + K_C) / M_W, -D_C / M_W]]),
        np.array([[0, 0], [K_C / M_W, D_C / M_W]]),
        np.array([[K_C, D_C]]),
        np.array([[-K_C, -D_C]]),
    ),
}


def quarter_car(tmp_path, split, H, steps):
    data = {
        "subsystems": {
            n: {"fmu": str(OM / f"QuarterCarModel.{split}.{n}.fmu"), "interface": "model-exchange"}
            for n in ("Chassis", "Wheel")
        },
        "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u in QUARTER_CAR[split]],
        "coupling": {"H": H},
        "t_end": steps * H,
    }
    data["subsystems"]["Wheel"]["start"] = {"z": 0.1}
    path = tmp_path / f"qc_{split}_{H:g}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_quarter_car_split_by_force_is_unstable_above_its_predicted_step(tmp_path):
    probe = predict_signal_scene(load_scene(quarter_car(tmp_path, "DisplacementForce", 1e-3, 1)))
    for name, u in probe["units"].items():
        got = [np.array(u[key]) for key in "ABCD"]
        for s in (0.5, 1j, 60j, 3 + 40j):  # not 0: the chassis is a free mass
            assert transfer(*got, s) == pytest.approx(transfer(*QUARTER_CAR_DF[name], s), rel=1e-7, abs=1e-9)
    limit = probe["largest_stable_H"]
    assert limit["status"] == "bisected"
    H, steps = 1.5 * limit["H_max"], 300
    path = quarter_car(tmp_path, "DisplacementForce", H, steps)
    rho = predict_signal_scene(load_scene(path))["schemes"][0]["rho"]
    assert rho > 1.01
    run = run_signal_scene(load_scene(path))
    x = np.abs(np.asarray(run.series["Chassis.z_c"]))
    w = steps // 6
    measured = (np.max(x[steps - w + 1 :]) / np.max(x[steps // 2 : steps // 2 + w])) ** (
        1 / (steps - w + 1 - steps // 2)
    )
    assert abs(measured - rho) <= 0.05 * (rho - 1), (measured, rho)


def test_the_quarter_car_split_by_displacements_is_predicted_stable_and_stays_bounded(tmp_path):
    H, steps = 0.05, 400
    answer = predict_signal_scene(load_scene(quarter_car(tmp_path, "DisplacementDisplacement", H, steps)))
    assert (
        answer["schemes"][0]["verdict"] == "stable" and answer["largest_stable_H"]["status"] == "stable up to the cap"
    )
    run = run_signal_scene(load_scene(quarter_car(tmp_path, "DisplacementDisplacement", H, steps)))
    z = np.asarray(run.series["Chassis.z_c"])
    assert run.status == "completed" and abs(z[-1] - 0.1) < 1e-3  # settled on the road's 0.1 m


def test_a_loop_of_direct_feedthrough_is_refused_before_a_unit_is_opened(tmp_path, monkeypatch):
    """The Reference-FMUs' Feedthrough twice, each fed by the other (as test_signals_outside's run refuses it)."""
    path = feedthrough_loop_scene(tmp_path)
    monkeypatch.setattr(predict_signals, "_open", lambda *a: pytest.fail("a unit was opened"))
    with pytest.raises(SceneError, match=r"algebraic loop .*a\.Float64_continuous_output -> b\.Float64_continuous_"):
        predict_signal_scene(load_scene(path))


def test_units_without_states_are_their_feedthrough(tmp_path):
    """The Reference-FMUs' Feedthrough (Co-Simulation, no states: its continuous output is its continuous input), a
    chain with no cycle of feedthrough: ``D`` is 1 where the output follows the input and 0 where it does not, and
    the recurrence is nilpotent (rho 0, whatever H)."""
    fmu = OUTSIDE / "reference-fmus" / "fmus2" / "Feedthrough.fmu"
    data = {
        "subsystems": {"a": {"fmu": str(fmu)}, "b": {"fmu": str(fmu)}},
        "connections": [
            {"from": "a.Float64_continuous_output", "to": "b.Float64_continuous_input", "factor": 2.0},
            {"from": "b.Float64_continuous_output", "to": "a.Float64_discrete_input"},
        ],
        "coupling": {"H": 0.1},
        "t_end": 1.0,
    }
    path = tmp_path / "chain.yaml"
    path.write_text(yaml.safe_dump(data))
    answer = predict_signal_scene(load_scene(path))
    assert answer["units"]["a"]["states"] == [] and answer["units"]["a"]["D"] == [[pytest.approx(0.0, abs=1e-12)]]
    assert answer["units"]["b"]["D"] == [[pytest.approx(1.0, abs=1e-12)]]
    for row in answer["schemes"]:
        assert row["verdict"] == "stable" and row["rho"] <= row["rho_error"], row
    assert answer["largest_stable_H"]["status"] == "stable up to the cap"
