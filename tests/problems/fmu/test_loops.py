"""Algebraic loops of signal connections, solved at each communication point by Newton's method without a step
(:mod:`icosim.problems.fmu.loops`).

What the tests compare follows from an independent computation, not from the code under test:

* a nonlinear loop of two of fmus/static_map (``f``: ``y = c sin(u) + b``, ``g``: ``y = u``) has the fixed points
  of ``u = 2 sin(u) + 0.3``, three of them; scipy's brentq on that scalar equation in a bracket with a sign change
  gives the root Newton's method is expected to find from each start;
* a linear loop with a state, fmus/msd's acceleration fed back by fmus/pcontrol (``lambda = kp (r - a)``, ``a =
  (-c x - d v + lambda) / m``): the loop eliminated by hand gives ``lambda (1 + kp / m) = kp r + kp / m (c x + d v)``,
  at ``t0`` by hand and over time as an ODE for scipy's solve_ivp; the co-simulation converges to it with the order
  of the inputs' extrapolation, ``k + 1``;
* ``kp = -m`` makes the loop gain 1 (``I - J`` singular): refused naming the loop;
* the Reference-FMUs' Feedthrough (another tool's unit) passes its input to its output: two of them fed by each
  other with factor ``f`` and offset ``o`` have the loop values ``u_a = o / (1 - f)``, ``u_b = f u_a``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from helpers import FMU_CACHE, ROOT
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from toolchains import OUTSIDE

from icosim.order_fit import asymptotic_order
from icosim.problems.fmu.build import build_unit
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.loops import LoopError
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import run_signal_scene, signal_dataset

pytestmark = pytest.mark.fmu

#: f's map and its fixed-point equation u = 2 sin(u) + 0.3: roots in (-2, -1), (-1, 0) and (2, 3).
C, B = 2.0, 0.3
M, CS, D, X0 = 1.0, 1000.0, 2.0, 0.1  # fmus/msd's mass (defaults but x0)
KP, R = 50.0, 0.2


def fixed_point(lo, hi):
    return brentq(lambda u: u - C * np.sin(u) - B, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)


def within(root, tolerance=1e-10):
    """How far a value whose residual u - 2 sin(u) - 0.3 is within ``tolerance * max(1, |u|)`` (the loop's test) can
    be from ``root``: the residual over its derivative 1 - 2 cos(u), and rounding."""
    return tolerance * max(1.0, abs(root)) / abs(1 - C * np.cos(root)) + 1e-15


def write(tmp_path, data, name="loop.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return load_scene(path)


def map_loop(tmp_path, output="y", start=0.0, **coupling):
    unit = str(build_unit(ROOT / "fmus" / "static_map", FMU_CACHE))
    return write(tmp_path, {
        "subsystems": {"f": {"fmu": unit, "start": {"a": 0.0, "b": B, "c": C, "u": start}}, "g": {"fmu": unit}},
        "connections": [{"from": f"f.{output}", "to": "g.u"}, {"from": "g.y", "to": "f.u"}],
        "coupling": {"H": 0.1, **coupling},
        "t_end": 0.5,
    })  # fmt: skip


def control_loop(tmp_path, kp, H, k=0, t_end=1.0, source=False, scheme="jacobi"):
    """The reference ``r`` a start value, or (``source``) a constant source."""
    msd, control = (str(build_unit(ROOT / "fmus" / n, FMU_CACHE)) for n in ("msd", "pcontrol"))
    return write(tmp_path, {
        "subsystems": {"mass": {"fmu": msd, "start": {"x0": X0}, "record": ["x"]},
                       "ctrl": {"fmu": control, "start": {"kp": kp, **({} if source else {"r": R})}}},
        "connections": [{"from": "ctrl.u", "to": "mass.lambda"}, {"from": "mass.a", "to": "ctrl.y"}],
        **({"sources": [{"to": "ctrl.r", "value": R}]} if source else {}),
        "coupling": {"H": H, "k": k, "scheme": scheme, **({"order": ["mass", "ctrl"]} if scheme != "jacobi" else {})},
        "t_end": t_end,
    })  # fmt: skip


@pytest.mark.parametrize("start, bracket", [(0.0, (-1.0, 0.0)), (2.5, (2.0, 3.0)), (-1.5, (-2.0, -1.0))])
def test_a_nonlinear_loop_is_solved_to_the_root_brentq_finds_and_says_which(tmp_path, start, bracket):
    """From each start Newton's method finds the root of the bracket around it (g'(u) = 1 - 2 cos(u) keeps its sign
    between them); the root and its start are said in the dataset, the loop named nonlinear."""
    root = fixed_point(*bracket)
    run = run_signal_scene(map_loop(tmp_path, start=start))
    assert run.status == "completed"
    for name in ("f.u", "g.u", "g.y"):  # every point: the states fixed, the root stays
        np.testing.assert_allclose(run.series[name], root, rtol=0, atol=within(root))
    ds = signal_dataset(run)
    assert ds.attrs["loop_connections"] == "f.y -> g.u, g.y -> f.u" and ds.attrs["loop_nonlinear"] == 1
    assert ds.attrs["loop_directional"] == "f, g"  # static_map gives its derivatives: no differences taken
    assert json.loads(ds.attrs["loop_start_t0"]) == [0.0, start]  # g.u starts at 0, f.u at its start value
    np.testing.assert_allclose(json.loads(ds.attrs["loop_root_t0"]), [root, root], atol=within(root))
    assert "nonlinear and may have several roots" in ds.attrs["loop_message"]
    assert ds.attrs["loop_solves"] == 6 and ds.attrs["loop_largest_residual"] <= 1e-10  # t0 and 5 steps


def test_a_dependency_the_structure_does_not_give_is_measured(tmp_path):
    """f.w and f.z give no dependencies in the ModelStructure: w is y (measured dependent, the loop is solved), z is
    b (measured independent: no loop, the connections coupled explicitly as before)."""
    run = run_signal_scene(map_loop(tmp_path, "w", start=-1.5))
    root = fixed_point(-2.0, -1.0)
    np.testing.assert_allclose(run.series["f.u"], root, atol=within(root))
    assert run.loop["loop_connections"] == "f.w -> g.u, g.y -> f.u"
    run = run_signal_scene(map_loop(tmp_path, "z"))
    assert run.loop == {} and run.series["g.u"] == [B] * 6 and run.series["f.u"][1:] == [B] * 5


def test_a_loop_that_does_not_converge_in_its_iterations_is_refused_naming_it(tmp_path):
    with pytest.raises(LoopError, match=r"algebraic loop f\.y -> g\.u, g\.y -> f\.u at t = 0 s: Newton's method "
                       r"has not converged in coupling\.loop_iterations = 1 steps"):  # fmt: skip
        run_signal_scene(map_loop(tmp_path, start=2.5, loop_iterations=1))


@pytest.mark.parametrize("key, value, says", [
    ("loop_tolerance", 0.0, "must be a number in (0, 1)"), ("loop_tolerance", "1e-8", "must be a number in (0, 1)"),
    ("loop_tolerance", True, "must be a number"), ("loop_iterations", 0, "must be an integer >= 1"),
    ("loop_iterations", 2.5, "must be an integer >= 1"),
])  # fmt: skip
def test_bad_loop_keys_are_refused_naming_the_key(tmp_path, key, value, says):
    with pytest.raises(SceneError) as refused:
        map_loop(tmp_path, **{key: value})
    assert f"coupling.{key}: {says}" in str(refused.value), str(refused.value)


@pytest.mark.parametrize("source", [False, True])
def test_a_linear_loop_with_a_state_is_solved_at_t0_as_by_hand(tmp_path, source):
    run = run_signal_scene(control_loop(tmp_path, KP, 1e-3, t_end=1e-3, source=source))
    lam = (KP * R + KP / M * CS * X0) / (1 + KP / M)
    np.testing.assert_allclose(run.series["mass.lambda"][0], lam, rtol=1e-13)
    np.testing.assert_allclose(run.series["mass.a"][0], (-CS * X0 + lam) / M, rtol=1e-12)
    assert run.loop["loop_nonlinear"] == 0 and "is linear" in run.loop["loop_message"]


def monolithic_x(t_end):
    """The mass's position with the loop eliminated by hand, by solve_ivp."""

    def rhs(t, z):
        x, v = z
        lam = (KP * R + KP / M * (CS * x + D * v)) / (1 + KP / M)
        return [v, (-CS * x - D * v + lam) / M]

    return solve_ivp(rhs, (0.0, t_end), [X0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15).y[0, -1]


@pytest.mark.parametrize("k, scheme", [(0, "jacobi"), (1, "jacobi"), (1, "gauss-seidel")])
def test_a_solved_loop_converges_to_the_monolithic_solution_with_order_k_plus_one(tmp_path, k, scheme):
    """Gauss-Seidel too: the loop is solved once both units stand at T_N+1, after the second stage."""
    Hs = [4e-3, 2e-3, 1e-3]
    ref = monolithic_x(1.0)
    errors = [abs(run_signal_scene(control_loop(tmp_path, KP, H, k, scheme=scheme)).series["mass.x"][-1] - ref)
              for H in Hs]  # fmt: skip
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - (k + 1)) < 0.15, (errors, fit)


def test_coupled_implicitly_the_corrector_closes_the_loop_with_order_two(tmp_path):
    """Implicit coupling (k = 1) closes the loop's conditions at T_N+1 with the other connections: the loop solver
    serves t0 only, Newton takes one iteration (the units are linear), and the run converges to the monolithic
    solution with the order of its interpolation, 2."""
    Hs = [4e-3, 2e-3, 1e-3]
    ref, errors = monolithic_x(1.0), []
    for H in Hs:
        scene = control_loop(tmp_path, KP, H, 1)
        scene.data["coupling"]["implicit"] = True
        run = run_signal_scene(write(tmp_path, scene.data, f"implicit_{H:g}.yaml"))
        assert run.loop["loop_solves"] == 1 and max(run.iterations) <= 2, (run.loop, max(run.iterations))
        errors.append(abs(run.series["mass.x"][-1] - ref))
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - 2) < 0.15, (errors, fit)


def test_a_loop_of_gain_one_is_refused_as_ill_posed(tmp_path):
    """kp = -m: lambda = -m (r - a) and a = (... + lambda) / m make d(lambda)/d(lambda) = 1 around the loop."""
    with pytest.raises(LoopError, match=r"algebraic loop ctrl\.u -> mass\.lambda, mass\.a -> ctrl\.y is ill-posed "
                       r"at t = 0 s: I - J .* is singular"):  # fmt: skip
        run_signal_scene(control_loop(tmp_path, -M, 1e-3))


def test_a_loop_of_another_tools_feedthrough_units_is_solved(tmp_path):
    """Two of the Reference-FMUs' Feedthrough, ``b.in = 0.5 a.out`` and ``a.in = b.out + 1``: ``a.in = 2``,
    ``b.in = 1`` at every point."""
    fmu = str(OUTSIDE / "reference-fmus" / "fmus2" / "Feedthrough.fmu")
    run = run_signal_scene(write(tmp_path, {
        "subsystems": {"a": {"fmu": fmu}, "b": {"fmu": fmu}},
        "connections": [
            {"from": "a.Float64_continuous_output", "to": "b.Float64_continuous_input", "factor": 0.5},
            {"from": "b.Float64_continuous_output", "to": "a.Float64_continuous_input", "offset": 1.0},
        ],
        "coupling": {"H": 0.1},
        "t_end": 1.0,
    }))  # fmt: skip
    np.testing.assert_allclose(run.series["a.Float64_continuous_input"], 2.0, rtol=1e-14)
    np.testing.assert_allclose(run.series["b.Float64_continuous_input"], 1.0, rtol=1e-14)


#: OMSimulator's DualMassOscillator.System1 (m1 1 kg, k1 10 N/m, c1 0.2 N s/m; its a1 depends on F directly, by its
#: ModelStructure) with fmus/pcontrol feeding back a1: the loop F = kp (r - a1), another tool's unit in it.
M1, K1, C1 = 1.0, 10.0, 0.2
KP1 = 3.0


def om_loop(tmp_path, interface, H, k=0):
    s1 = {"fmu": str(OUTSIDE / "omsimulator" / "DualMassOscillator.System1.fmu"), "start": {"x1_start": X0},
          "interface": interface, "record": ["x1"]}  # fmt: skip
    if interface == "model-exchange":
        s1["tolerance"] = 1e-12
    control = str(build_unit(ROOT / "fmus" / "pcontrol", FMU_CACHE))
    return write(tmp_path, {
        "subsystems": {"s1": s1, "ctrl": {"fmu": control, "start": {"kp": KP1, "r": R}}},
        "connections": [{"from": "ctrl.u", "to": "s1.F"}, {"from": "s1.a1", "to": "ctrl.y"}],
        "coupling": {"H": H, "k": k},
        "t_end": 2.0,
    })  # fmt: skip


@pytest.mark.parametrize("interface", ["co-simulation", "model-exchange"])
def test_another_tools_unit_in_a_loop_is_solved_at_t0_as_by_hand(tmp_path, interface):
    """Both of OpenModelica's interfaces give a1 from F without a step: at t0 F (1 + kp / m1) = kp r + kp / m1 k1 x0."""
    scene = om_loop(tmp_path, interface, 1e-2)
    scene.t_end = 1e-2
    run = run_signal_scene(scene)
    np.testing.assert_allclose(run.series["s1.F"][0], (KP1 * R + KP1 / M1 * K1 * X0) / (1 + KP1 / M1), rtol=1e-12)


@pytest.mark.parametrize("k", [0, 1])
def test_a_loop_with_a_model_exchange_unit_converges_with_order_k_plus_one(tmp_path, k):
    """System1 as Model Exchange (integrated by icosim to 1e-12): the loop eliminated by hand, by solve_ivp."""

    def rhs(t, z):
        x, v = z
        force = (KP1 * R + KP1 / M1 * (K1 * x + C1 * v)) / (1 + KP1 / M1)
        return [v, (-K1 * x - C1 * v + force) / M1]

    ref = solve_ivp(rhs, (0.0, 2.0), [X0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15).y[0, -1]
    Hs = [4e-3, 2e-3, 1e-3]
    errors = [abs(run_signal_scene(om_loop(tmp_path, "model-exchange", H, k)).series["s1.x1"][-1] - ref) for H in Hs]
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - (k + 1)) < 0.15, (errors, fit)


def test_the_command_line_says_which_root_it_found_and_the_file_keeps_it(tmp_path, capsys):
    from icosim.cli import main
    from icosim.io.netcdf import open_dataset

    scene = map_loop(tmp_path, start=2.5)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(scene.path), "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "loop: the algebraic loop f.y -> g.u, g.y -> f.u is nonlinear and may have several roots" in said
    with open_dataset(out) as ds:
        root = fixed_point(2.0, 3.0)
        np.testing.assert_allclose(json.loads(ds.attrs["loop_root_t0"]), [root, root], atol=within(root))
        assert json.loads(ds.attrs["loop_start_t0"]) == [0.0, 2.5]


def test_the_command_line_refuses_an_ill_posed_loop_naming_it_and_writes_nothing(tmp_path, capsys):
    from icosim.cli import main

    scene = control_loop(tmp_path, -M, 1e-3)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(scene.path), "--out", str(out)]) != 0
    said = capsys.readouterr().err
    assert "ctrl.u -> mass.lambda, mass.a -> ctrl.y is ill-posed" in said and not out.exists()


def test_a_nonlinear_loop_with_a_state_converges_to_the_monolithic_solution_with_order_two(tmp_path):
    """fmus/msd's acceleration into fmus/static_map, ``lambda = -0.5 a + sin(a)``, back into the force: at each
    state ``1.5 a - sin(a) = -c x - d v`` (one root: its derivative is at least 0.5), solved by brentq inside
    solve_ivp; the loop's Jacobian moves with the state, so Newton takes fresh ones along the run.  k = 1: order 2."""
    msd, unit = (str(build_unit(ROOT / "fmus" / n, FMU_CACHE)) for n in ("msd", "static_map"))
    x0 = 0.002  # accelerations of order 1, over which sin bends

    def acceleration(x, v):
        return brentq(lambda q: 1.5 * q - np.sin(q) + CS * x + D * v, -1e4, 1e4, xtol=1e-14)

    ref = solve_ivp(lambda t, z: [z[1], acceleration(*z)], (0.0, 1.0), [x0, 0.0], method="DOP853", rtol=1e-12,
                    atol=1e-14).y[0, -1]  # fmt: skip
    Hs, errors = [4e-3, 2e-3, 1e-3], []
    for H in Hs:
        run = run_signal_scene(write(tmp_path, {
            "subsystems": {"mass": {"fmu": msd, "start": {"x0": x0}, "record": ["x"]},
                           "f": {"fmu": unit, "start": {"a": -0.5, "c": 1.0}}},
            "connections": [{"from": "f.y", "to": "mass.lambda"}, {"from": "mass.a", "to": "f.u"}],
            "coupling": {"H": H, "k": 1},
            "t_end": 1.0,
        }))  # fmt: skip
        errors.append(abs(run.series["mass.x"][-1] - ref))
        assert (
            run.loop["loop_nonlinear"] == 1 and run.loop["loop_jacobians"] > 10 and run.loop["loop_directional"] == "f"
        )
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - 2) < 0.15, (errors, fit)
