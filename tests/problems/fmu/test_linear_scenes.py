"""FMU scenes against the built-in linear model: the same trajectories (every method, k = 0..2, every scheme and
decomposition), the growth per macro step of an unstable scene equal to the spectral radius, the doStep counts.

The test units are built from fmus/ with fmpy (CMake and a C compiler); without them the tests are skipped.
"""

import numpy as np
import pytest
from helpers import ROOT

from icosim.engine.methods import engine_method, make_method
from icosim.engine.run import simulate
from icosim.problems.fmu.run import run_scene
from icosim.problems.fmu.scene import COUPLING_KEYS
from icosim.problems.linear.model import PhysicalModel
from icosim.problems.linear.problem import LinearCosimulation
from icosim.problems.linear.spectral import spectral_radius_float64
from icosim.studies.fmi.orders import order_scene

pytestmark = pytest.mark.fmu

P = dict(m1=1.0, m2=2.0, c1=1000.0, c2=500.0, d1=2.0, d2=1.0)
PARAMS = {"baumgarte": {"index": 1, "mu": 1e-3}, "weighted": {"index": 1, "a": 1.0, "b": 1.0}, "projection": {}}
SCHEMES = ("jacobi", "gauss-seidel-12", "gauss-seidel-21")
X0 = 0.1


def write_scene(path, method, decomposition, k, scheme, H, n, **coupling):
    """The two-mass scene on the msd units, written into path's folder by the library's own scene builder (the
    convergence orders' one: the scene is the setup here, not what is checked); the perturbation is the scene
    default unless given.  The coupling variables start at zero and no bound stops a growing run: an unstable
    configuration's unstable mode then starts at the size of the start's inconsistency, not of rounding, so the
    two implementations stay within rounding of each other relative to the largest value (from a consistent
    start, tests/problems/fmu/test_unit_checks.py)."""
    params = {"perturbation": COUPLING_KEYS["perturbation"]} | PARAMS[method] | coupling
    n_e = 2 if decomposition in ("fd", "df") else 1
    scene = {"initial_coupling": [0.0] * n_e, "divergence_bound": 1e300}
    case = {"method": method, "decomposition": decomposition, "k": k, "scheme": scheme, "params": params}
    return order_scene(path.parent, ROOT / "fmus", P, X0, case | {"scene": scene}, H, n * H)


def builtin(method, decomposition, k, scheme, H, n):
    """Positions and velocities (SI) of the built-in linear model from the same start."""
    problem = LinearCosimulation(PhysicalModel(H=H, **P).coefficients(), decomposition, k)
    state, history = np.array([[X0, 0.0], [X0, 0.0]]), np.zeros((k + 1, problem.n_coupling))
    traj = simulate(problem, engine_method(make_method(method, **PARAMS[method]), H), state, history, n, scheme=scheme)
    s = np.array(traj.states)
    return s[..., 0], s[..., 1] / H


def relative_difference(run, method, decomposition, k, scheme, H, n):
    x, v = builtin(method, decomposition, k, scheme, H, n)
    assert len(x) == len(run.times) == n + 1
    dx = np.max(np.abs(run.states[..., 0] - x)) / max(1.0, np.max(np.abs(x)))
    dv = np.max(np.abs(run.states[..., 1] - v)) / max(1.0, np.max(np.abs(v)))
    return max(dx, dv)


CASES = [
    (method, dec, k, scheme)
    for dec in ("ff", "fd", "df", "dd")
    for method in PARAMS
    if dec != "dd" or method == "projection"
    for k in (0, 1, 2)
    for scheme in SCHEMES
]


@pytest.mark.parametrize("method, decomposition, k, scheme", CASES, ids=lambda v: str(v))
def test_fmu_scene_follows_the_builtin_model(tmp_path, method, decomposition, k, scheme):
    """Same trajectory within 1e-9 (relative to the largest value: some of these configurations are unstable and
    grow by many orders of magnitude; the stable ones agree to about 1e-13)."""
    H, n = 1e-3, 80
    run = run_scene(write_scene(tmp_path / "s.yaml", method, decomposition, k, scheme, H, n, perturbation=1.0))
    assert run.status == "completed"
    assert relative_difference(run, method, decomposition, k, scheme, H, n) < 1e-9


def test_default_perturbation_is_close_enough_for_a_stable_scene(tmp_path):
    """The default difference step (1e-3 relative) loses a few digits of the sensitivities to rounding; a stable
    run still agrees to far better than 1e-9."""
    H, n = 1e-3, 300
    run = run_scene(write_scene(tmp_path / "s.yaml", "baumgarte", "fd", 1, "jacobi", H, n))
    assert relative_difference(run, "baumgarte", "fd", 1, "jacobi", H, n) < 1e-9


def test_growth_per_macro_step_is_the_spectral_radius(tmp_path):
    """Weighted multiplier, ff, k = 2, Jacobi at H = 1 ms (near the origin of the stability plots): unstable,
    and the FMU run grows by rho per macro step."""
    H, n = 1e-3, 400
    method = engine_method(make_method("weighted", **PARAMS["weighted"]), H)
    rho, _ = spectral_radius_float64(PhysicalModel(H=H, **P).coefficients(), method, "ff", 2, scheme="jacobi")
    rho = float(rho)
    assert rho > 1.1
    run = run_scene(write_scene(tmp_path / "s.yaml", "weighted", "ff", 2, "jacobi", H, n, perturbation=1.0))
    amp = np.max(np.abs(run.states[..., 0]), axis=1)
    early, late = np.max(amp[150:200]), np.max(amp[350:400])
    growth = (late / early) ** (1 / 200)
    assert growth == pytest.approx(rho, rel=1e-3)


@pytest.mark.parametrize(
    "scheme, sensitivities, iterations, per_step",
    [
        ("jacobi", "each-step", 1, 6),  # 2 predictors, 2 perturbed correctors, 2 correctors
        ("gauss-seidel-12", "each-step", 1, 4),  # leader once, the other predicted, perturbed, corrected
        ("jacobi", "first-step", 1, 4),
        ("gauss-seidel-21", "first-step", 1, 3),
        ("jacobi", "each-step", 2, 10),  # a second pass: perturbed correctors and correctors again
        ("gauss-seidel-12", "each-step", 2, 6),
        ("jacobi", "first-step", 2, 6),
        ("gauss-seidel-21", "first-step", 2, 4),
    ],
)
def test_do_step_calls_per_macro_step(tmp_path, scheme, sensitivities, iterations, per_step):
    n = 20
    scene = write_scene(
        tmp_path / "s.yaml", "projection", "ff", 1, scheme, 1e-3, n, sensitivities=sensitivities, iterations=iterations
    )
    run = run_scene(scene)
    calls = sum(u["do_step_calls"] for u in run.units.values())
    perturbed = 2 if scheme == "jacobi" else 1  # the first macro step computes the sensitivities in both cases
    first = per_step + (perturbed if sensitivities == "first-step" else 0)
    assert calls == first + per_step * (n - 1)
    assert relative_difference(run, "projection", "ff", 1, scheme, 1e-3, n) < 1e-11


def test_sub_steps_approximate_the_polynomial_input(tmp_path):
    """Units sampled at sub-step midpoints instead of given the input's derivatives: second order in the
    sub-step (the error falls by about 4 when the sub-steps double)."""
    H, n = 1e-3, 100
    x, _ = builtin("projection", "ff", 2, "jacobi", H, n)
    errors = []
    for m in (4, 8):
        scene = write_scene(tmp_path / "s.yaml", "projection", "ff", 2, "jacobi", H, n, inputs="substeps", substeps=m)
        run = run_scene(scene)
        assert all(u["inputs"] == f"substeps ({m})" for u in run.units.values())
        errors.append(np.max(np.abs(run.states[..., 0] - x)))
    assert 0 < errors[1] < errors[0] / 3
