"""Drives by position, velocity and acceleration (docs/fmi.md): a kinematically driven unit whose inputs are its
point's position, velocity and acceleration and which has no outputs for them (fmus/move_oscillator, OMSimulator's
DualMassOscillator.System2 as a C unit), joined to a force-driven mass (fmus/msd with System1's parameters).

The exact solution is the monolithic two-mass oscillator of DualMassOscillator.mo (ReferenceSystemEq), solved by
the matrix exponential; the orders of convergence are those of the built-in linear two-mass model under the same
method, ``k`` and decomposition (the two-unit study), computed here from the built-in model.
"""

import numpy as np
import pytest
import yaml
from helpers import ROOT

from icosim.engine.methods import engine_method, make_method
from icosim.engine.run import simulate
from icosim.order_fit import asymptotic_order
from icosim.problems.fmu.dual_mass import DualMass
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.predict import predict_scene
from icosim.problems.fmu.problem import FmuCosimulation
from icosim.problems.fmu.run import open_units, run_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.linear.exact import MonolithicSolution, consistent_start
from icosim.problems.linear.model import PhysicalModel
from icosim.problems.linear.problem import LinearCosimulation

pytestmark = pytest.mark.fmu

# DualMassOscillator.mo: System1 (m1, k1, c1), System2 (k2, c2 to m2, k3, c3 to the ground), x2_start 0.5
M1, K1, C1, K2, C2, K3, C3, M2 = 1.0, 10.0, 0.2, 10.0, 0.5, 20.0, 0.3, 1.0
AMPLITUDE = 0.5  # x2_start: the largest displacement of the free oscillation
DUAL_MASS = DualMass(m1=M1, k1=K1, c1=C1, m2=M2, k2=K2, c2=C2, k3=K3, c3=C3, x1_start=0.0, x2_start=AMPLITUDE)
A = DUAL_MASS.matrix
#: x1, x2, v1, v2 of the monolithic system at the times ``t``, ``(len(t), 4)`` (the library's exact solution).
exact = DUAL_MASS.exact


def exact_coupling(t, decomposition):
    """The coupling variables at ``t``: lambda_c the force on mass 1 (System2's F), a_tilde its acceleration."""
    x1, x2, v1, v2 = exact([t])[0]
    force, acc = K2 * (x2 - x1) + C2 * (v2 - v1), (A @ [x1, x2, v1, v2])[2]
    return [acc] if decomposition == "dd" else [force, acc]


MASS = {
    "fmu": str(ROOT / "fmus" / "msd"),
    "start": {"m": M1, "c": K1, "d": C1, "x0": 0.0},
    "position": "x",
    "velocity": "v",
    "acceleration": "a",
    "force": "lambda",
    "mass": M1,
    "set_position": "x_set",
    "set_velocity": "v_set",
}
KINEMATIC_MASS = {
    "fmu": str(ROOT / "fmus" / "msd_kinematic"),
    "start": {"m": M1, "c": K1, "d": C1, "x0": 0.0},
    "position": "x",
    "velocity": "v",
    "acceleration": "a",
    "acceleration_input": "a_in",
    "reaction_force": "F",
    "mass": M1,
    "set_position": "x_set",
    "set_velocity": "v_set",
}
MOVE = {
    "fmu": str(ROOT / "fmus" / "move_oscillator"),
    "position_input": "x1",
    "velocity_input": "v1",
    "acceleration_input": "a1",
    "reaction_force": "F",
}
PARAMS = {
    "projection": {},
    "baumgarte": {"index": 1, "mu": 1e-3},
    "weighted": {"index": 1, "a": 1.0, "b": 1.0},
}


def write(tmp_path, method, k, H, t_end, decomposition="fd", *, params=None, move=None, scheme="jacobi", **top):
    """The scene: the mass (System1) and the Move-driven oscillator (System2), as the decomposition orders them;
    System2's F is the force on mass 1, so it reads with the sign of the multiplier on the first side."""
    move = MOVE | (move or {})
    one = (KINEMATIC_MASS if decomposition == "dd" else MASS) | {"force_sign": 1}
    if decomposition == "df":
        subs = {"system2": move | {"force_sign": -1}, "system1": MASS | {"force_sign": -1}}
    else:
        subs = {"system1": one, "system2": move | {"force_sign": 1}}
    params = PARAMS[method] if params is None else params
    data = {
        "subsystems": subs,
        "coupling": {
            "method": method,
            "decomposition": decomposition,
            "k": k,
            "H": H,
            "scheme": scheme,
            "perturbation": 1.0,
            **params,
        },
        "t_end": t_end,
        **top,
    }
    path = tmp_path / f"drive_{method}_{decomposition}_{k}_{H:g}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def mass1(run, decomposition):
    """Mass 1's position over the run (the driven point's: the joint holds it to mass 1)."""
    return run.states[:, 1 if decomposition == "df" else 0, 0]


def exact_start_positions(scene, decomposition="fd"):
    """Mass 1's position over a run of ``scene`` from the exact start (the coupling history at ``T_0 ... T_-k``
    the exact solution's; mass 1 is the first unit, or the second with df)."""
    c = scene.coupling
    k, H = c["k"], c["H"]
    units, couplings = open_units(scene)
    problem = FmuCosimulation(units, couplings, decomposition, k, H, perturbation=1.0)
    try:
        history = np.array([exact_coupling(-j * H, decomposition) for j in range(k + 1)])
        if decomposition == "df":
            history = history * [-1.0, 1.0]  # the multiplier acts on the first side: -F on system2's point
        with np.errstate(all="ignore"):
            traj = simulate(problem, scene.method, problem.initial_state(), history, scene.n_steps)
    finally:
        problem.close()
        for unit in units:
            unit.close()
    return np.array(traj.states)[:, 1 if decomposition == "df" else 0, 0]


def exact_start_errors(tmp_path, method, k, Hs, t_end, decomposition="fd", params=None):
    """The largest error of mass 1's position over ``[0, t_end]`` at each ``H``, from the exact start."""
    errors = []
    for H in Hs:
        scene = load_scene(write(tmp_path, method, k, H, t_end, decomposition, params=params))
        x = exact_start_positions(scene, decomposition)
        t = H * np.arange(len(x))
        errors.append(float(np.max(np.abs(x - exact(t)[:, 0]))) if len(x) == scene.n_steps + 1 else np.nan)
    return errors


def builtin_order(method, k, Hs, decomposition="fd", params=None, scheme="jacobi", h_scale=1.0):
    """The asymptotic order of the built-in linear two-mass model (the two-unit study's model, the linear
    convergence study's parameters) under the same method, k, decomposition and scheme, from the exact start, at
    the step sizes ``h_scale * Hs`` (its oscillation is about six times faster than the oscillator's: a scheme
    stable on the oscillator may need smaller steps there)."""
    model = dict(m1=1.0, m2=2.0, c1=1000.0, c2=1000.0, d1=10.0, d2=10.0)
    params = PARAMS[method] if params is None else params
    errors = []
    for h in np.asarray(Hs) * h_scale:
        coeffs = PhysicalModel(H=h, **model).coefficients()
        problem, solution = LinearCosimulation(coeffs, decomposition, k), MonolithicSolution(coeffs, 0.1, 0.0)
        state, history = consistent_start(problem, solution)
        n = int(round(0.1 / h))
        with np.errstate(all="ignore"):
            traj = simulate(problem, engine_method(make_method(method, **params), h), state, history, n, scheme=scheme)
        x = np.array(traj.states)[..., 0]
        errors.append(
            float(np.max(np.abs(x - solution.state(np.arange(n + 1.0))[:, :1]))) if len(x) == n + 1 else np.nan
        )
    return asymptotic_order(Hs, errors).order


ORDER_CASES = [
    ("projection", 0, None),
    ("projection", 1, None),
    ("projection", 2, None),
    ("baumgarte", 0, None),
    ("baumgarte", 1, None),
    ("baumgarte", 2, None),
    ("baumgarte", 0, {"index": 2, "mu": 1e-3}),
    ("baumgarte", 0, {"index": 3}),
    ("weighted", 0, None),
    ("weighted", 1, None),
    ("weighted", 0, {"index": 2, "a": 1.0}),
]


@pytest.mark.parametrize("method, k, params", ORDER_CASES, ids=lambda v: str(v))
def test_drive_converges_with_the_orders_of_the_two_unit_study(tmp_path, method, k, params):
    """fd, every method and index at the k the two-unit study serves them: the error of mass 1 against the exact
    solution falls with the built-in model's order (within 0.1) and is asymptotic."""
    Hs = [2e-3, 1e-3, 5e-4, 2.5e-4]
    errors = exact_start_errors(tmp_path, method, k, Hs, 0.5, params=params)
    fit = asymptotic_order(Hs, errors)
    expected = builtin_order(method, k, Hs, params=params)
    assert fit.status == "asymptotic", (errors, fit)
    assert abs(fit.order - expected) < 0.1, (errors, fit.order, expected)


@pytest.mark.parametrize("method", ["projection", "baumgarte"])
def test_drive_meets_the_exact_solution_at_10_s(tmp_path, method):
    """k = 2 at H = 1e-3 from the computed start (the scene as a user runs it): mass 1 at t = 10 s within 1e-6 of
    the amplitude of the exact solution (x1(10 s) = 0.05104081, as OMSimulator's DualMassOscillator records)."""
    run = run_scene(write(tmp_path, method, 2, 1e-3, 10.0))
    assert run.status == "completed"
    x_exact = exact([10.0])[0, 0]
    assert abs(x_exact - 0.05104081) < 5e-9
    assert abs(mass1(run, "fd")[-1] - x_exact) < 1e-6 * AMPLITUDE


@pytest.mark.parametrize(
    "decomposition, method, scheme",
    [
        ("df", "projection", "jacobi"),
        ("df", "baumgarte", "jacobi"),
        ("dd", "projection", "jacobi"),
        ("fd", "weighted", "gauss-seidel-12"),
    ],
)
def test_drive_serves_every_decomposition(tmp_path, decomposition, method, scheme):
    """df (the drive first), dd (the drive against msd_kinematic, System1 as a kinematically driven mass) and
    Gauss–Seidel with the drive last: at k = 1 the error falls as H does twice over with the built-in model's
    order (within 0.15; Jacobi's: the built-in weighted multiplier under Gauss–Seidel 12 is unstable, its
    kinematically driven side being a mass), from the computed start."""
    Hs = [1e-3, 5e-4, 2.5e-4]
    errors = []
    for H in Hs:
        run = run_scene(write(tmp_path, method, 1, H, 0.5, decomposition, scheme=scheme))
        assert run.status == "completed"
        errors.append(float(np.max(np.abs(mass1(run, decomposition) - exact(run.times)[:, 0]))))
    slopes = np.diff(np.log(errors)) / np.diff(np.log(Hs))
    expected = builtin_order(method, 1, Hs, decomposition)  # Jacobi: its Gauss–Seidel 12 (weighted) is unstable
    assert np.all(np.abs(slopes - expected) < 0.15), (errors, slopes, expected)


def test_a_drive_without_the_acceleration_input_runs_the_same(tmp_path):
    """System2 does not read a1 (Move's massless point): driven by position and velocity alone, bit for bit the
    same run."""
    full = run_scene(write(tmp_path, "projection", 1, 1e-3, 0.2))
    move = {k: v for k, v in MOVE.items() if k != "acceleration_input"}
    path = write(tmp_path / "..", "projection", 1, 1e-3, 0.2)
    data = yaml.safe_load(path.read_text())
    data["subsystems"]["system2"] = move | {"force_sign": 1}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    bare = run_scene(path)
    np.testing.assert_array_equal(full.states, bare.states)


def test_a_drive_by_its_acceleration_alone_is_the_unit_that_integrates_itself(tmp_path):
    """msd_kinematic integrates its point from its acceleration input (Taylor sums, fmus/README.md); named with
    only its acceleration input and no position, velocity or acceleration output, the master prescribes the same
    kinematics from the coupling polynomial: the two runs agree to rounding."""
    path = ROOT / "config" / "scenes" / "two_mass_fd.yaml"
    data = yaml.safe_load(path.read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str((path.parent / sub["fmu"]).resolve())
    data["t_end"] = 0.2
    (tmp_path / "own.yaml").write_text(yaml.safe_dump(data))
    for key in ("position", "velocity", "acceleration"):
        del data["subsystems"]["body2"][key]
    (tmp_path / "prescribed.yaml").write_text(yaml.safe_dump(data))
    own, prescribed = run_scene(tmp_path / "own.yaml"), run_scene(tmp_path / "prescribed.yaml")
    scale = np.max(np.abs(own.states), axis=(0, 1))
    assert np.max(np.abs(own.states - prescribed.states) / scale) < 1e-11


def test_refusals_name_the_key(tmp_path):
    """What cannot be served is refused before any unit is loaded, naming the key and why."""

    def refused(edit, *needles):
        path = write(tmp_path, "projection", 1, 1e-3, 0.1)
        data = yaml.safe_load(path.read_text())
        edit(data)
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        with pytest.raises(SceneError) as info:
            load_scene(path)
        for needle in needles:
            assert needle in str(info.value), str(info.value)

    def no_drive_input(d):
        for key in ("position_input", "velocity_input", "acceleration_input"):
            del d["subsystems"]["system2"][key]

    refused(no_drive_input, "subsystems.system2.acceleration_input", "any of position_input, velocity_input")

    def force_with_drive(d):
        d["subsystems"]["system1"]["position_input"] = "x"

    refused(force_with_drive, "subsystems.system1.position_input", "force-driven")

    def force_without_position(d):
        del d["subsystems"]["system1"]["position"]

    refused(force_without_position, "subsystems.system1.position", "force-driven")

    def two_drives(d):
        d["coupling"]["decomposition"] = "dd"
        d["subsystems"]["system1"] = MOVE | {"force_sign": 1}

    refused(two_drives, "subsystems.system1.position", "nothing says where their joint is")

    def dd_baumgarte(d):
        two_drives(d)
        d["coupling"] |= {"method": "baumgarte", "index": 1, "mu": 1e-3}

    refused(dd_baumgarte, "coupling", "'dd'")


def test_predict_refuses_a_drive(tmp_path):
    with pytest.raises(SceneError, match=r"subsystems\.system2: --predict"):
        predict_scene(load_scene(write(tmp_path, "projection", 1, 1e-3, 0.1)))


def test_gauss_seidel_reevaluates_a_drive_whose_force_follows_its_point(tmp_path):
    """System2's force follows its point's position and velocity inputs without a step (not its acceleration, as
    Move's): Gauss–Seidel with the drive first re-evaluates it at its end state and converges with the built-in
    model's order under the same scheme (H small enough to be stable there)."""
    Hs = [5e-4, 2.5e-4, 1.25e-4]
    errors = []
    for H in Hs:
        run = run_scene(write(tmp_path, "baumgarte", 1, H, 0.25, scheme="gauss-seidel-21"))
        assert run.status == "completed"
        assert run.units["system2"]["feedthrough"] == "yes"
        errors.append(float(np.max(np.abs(mass1(run, "fd") - exact(run.times)[:, 0]))))
    slopes = np.diff(np.log(errors)) / np.diff(np.log(Hs))
    expected = builtin_order("baumgarte", 1, Hs, scheme="gauss-seidel-21", h_scale=1 / 8)
    assert np.all(np.abs(slopes - expected) < 0.15), (errors, slopes, expected)


def test_a_drive_closes_a_chain(tmp_path):
    """Mass 1 split into two halves joined ff, the drive joined to the second fd (joints: a drive's force_sign as
    any unit's with joints): the same motion as the two-unit scene, within 1e-6 of the amplitude at t = 2 s."""
    half = MASS | {"start": {"m": M1 / 2, "c": K1 / 2, "d": C1 / 2, "x0": 0.0}, "mass": M1 / 2, "force_sign": 1}
    data = {
        "subsystems": {
            "a": half,
            "b": half,
            "c": {k: v for k, v in MOVE.items() if k != "acceleration_input"} | {"force_sign": -1},
        },
        "joints": [{"between": ["a", "b"], "decomposition": "ff"}, {"between": ["b", "c"], "decomposition": "fd"}],
        "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "k": 2, "H": 1e-3, "perturbation": 1.0},
        "t_end": 2.0,
    }
    path = tmp_path / "chain.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    run = run_scene(path)
    assert run.status == "completed"
    assert np.max(np.abs(run.states[-1, :, 0] - exact([2.0])[0, 0])) < 1e-6 * AMPLITUDE
