"""Chains of FMU units (scenes with joints) against the built-in chain model (icosim.problems.linear.chain): the same
trajectories for every method, k = 0..2, Jacobi and two Gauss-Seidel orders, on 3 and 10 units (the 10 with a
kinematically driven unit at one end); the orders of convergence against the exact monolithic solution; the
growth per macro step of an unstable chain equal to the spectral radius; a chain written in another order;
--predict; the dataset, the start and --check; and every refusal of a scene's joints and order (exit 2).

The scenes are the setup, written here; the built-in chain is typed in with the same parameters.
"""

import json

import numpy as np
import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.engine.decompositions import get_decomposition
from icosim.engine.methods import engine_method, make_method
from icosim.engine.run import simulate
from icosim.engine.spectral.radius import spectral_radius_float64
from icosim.io.netcdf import open_dataset
from icosim.order_fit import asymptotic_order
from icosim.problems.fmu.predict import predict_scene
from icosim.problems.fmu.problem import FmuCosimulation
from icosim.problems.fmu.run import open_units, run_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.linear.chain import Chain, ChainFamily, ChainSegment, ChainSolution, chain_start

pytestmark = pytest.mark.fmu

FMUS = ROOT / "fmus"
#: m, c, d of the units, one per row: every unit different
UNITS = [(1.0, 1000.0, 2.0), (2.0, 500.0, 1.0), (0.5, 2000.0, 0.5), (1.5, 800.0, 1.5), (1.0, 1200.0, 3.0),
         (3.0, 300.0, 0.2), (0.8, 1500.0, 1.0), (1.2, 900.0, 2.5), (2.5, 700.0, 0.8), (1.0, 1000.0, 1.0)]  # fmt: skip
PARAMS = {"baumgarte": {"index": 1, "mu": 1e-3}, "weighted": {"index": 1, "a": 1.0, "b": 1.0}, "projection": {}}
X0 = 0.1


def unit(i, kind="force", x0=X0):
    m, c, d = UNITS[i]
    sub = {"start": {"m": m, "c": c, "d": d, "x0": x0}, "position": "x", "velocity": "v", "acceleration": "a",
           "force_sign": 1, "mass": "m", "set_position": "x_set", "set_velocity": "v_set"}  # fmt: skip
    if kind == "force":
        return sub | {"fmu": str(FMUS / "msd"), "force": "lambda"}
    return sub | {"fmu": str(FMUS / "msd_kinematic"), "acceleration_input": "a_in", "reaction_force": "F"}


def chain_scene(path, decompositions, method, k, scheme, H, n, *, x0=None, params=None, **top):
    """``len(decompositions) + 1`` units in a row, ``u1 ... uN``, joint ``j`` between ``u(j+1)`` and ``u(j+2)``
    with ``decompositions[j]``; the units' kinds follow the decompositions.  ``scheme``: a name, or an order of
    the units' names (``scheme: gauss-seidel`` with ``order``).  The coupling variables start at zero and no bound
    stops a growing run (as tests/problems/fmu/test_linear_scenes.py, for the same reason)."""
    N = len(decompositions) + 1
    kinds = ["force"] * N
    for j, d in enumerate(decompositions):
        for side, i in ((0, j), (1, j + 1)):
            if d[side] == "d":
                kinds[i] = "kinematic"
    x0 = [X0] * N if x0 is None else x0
    names = [f"u{i + 1}" for i in range(N)]
    coupling = {"method": method, "k": k, "H": float(H), "perturbation": 1.0} | (
        PARAMS[method] if params is None else params
    )
    if isinstance(scheme, str):
        coupling["scheme"] = scheme
    else:
        coupling |= {"scheme": "gauss-seidel", "order": list(scheme)}
    data = {
        "subsystems": {name: unit(i, kinds[i], x0[i]) for i, name in enumerate(names)},
        "joints": [{"between": [names[j], names[j + 1]], "decomposition": d} for j, d in enumerate(decompositions)],
        "coupling": coupling,
        "t_end": float(n * H),
        "initial_coupling": [0.0] * sum(get_decomposition(d).n_coupling for d in decompositions),
        "divergence_bound": 1e300,
    } | top
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def builtin_chain(decompositions, H):
    N = len(decompositions) + 1
    return Chain(tuple(ChainSegment((m,), (c,), (d,)) for m, c, d in UNITS[:N]), tuple(decompositions), H)


def builtin_run(decompositions, method, k, scheme, H, n):
    """Positions and velocities (SI, ``(n + 1, N)``) of the built-in chain from the scenes' start."""
    problem = builtin_chain(decompositions, H).problem(k)
    N = len(decompositions) + 1
    state, history = np.array([[X0, 0.0]] * N), np.zeros((k + 1, problem.n_coupling))
    traj = simulate(problem, engine_method(make_method(method, **PARAMS[method]), H), state, history, n, scheme=scheme)
    s = np.array(traj.states)
    return s[..., 0], s[..., 1] / H


def gs_name(order):
    sep = "" if len(order) < 10 else "."
    return "gauss-seidel-" + sep.join(str(int(u[1:])) for u in order)


def relative_difference(run, x, v):
    dx = np.max(np.abs(run.states[..., 0] - x)) / max(1.0, np.max(np.abs(x)))
    dv = np.max(np.abs(run.states[..., 1] - v)) / max(1.0, np.max(np.abs(v)))
    return max(dx, dv)


SHAPES = {3: ("ff", "ff"), 10: ("ff",) * 8 + ("fd",)}  # 10: the last unit kinematically driven by the ninth
CASES = [
    (N, method, k, scheme)
    for N in SHAPES
    for method in PARAMS
    for k in (0, 1, 2)
    for scheme in ("jacobi", "forward", "backward")
]


@pytest.mark.parametrize("N, method, k, scheme", CASES, ids=lambda v: str(v))
def test_fmu_chain_follows_the_builtin_chain(tmp_path, N, method, k, scheme):
    """Within 1e-9 relative to the largest value (several of these configurations are unstable and grow by many
    orders of magnitude; the stable ones agree to about 1e-13)."""
    H, n = 1e-3, 30 if N == 10 else 60
    names = [f"u{i + 1}" for i in range(N)]
    order = {"jacobi": "jacobi", "forward": names, "backward": names[::-1]}[scheme]
    run = run_scene(chain_scene(tmp_path / "s.yaml", SHAPES[N], method, k, order, H, n))
    assert run.status == "completed"
    name = order if isinstance(order, str) else gs_name(order)
    x, v = builtin_run(SHAPES[N], method, k, name, H, n)
    assert relative_difference(run, x, v) < 1e-9


def test_gauss_seidel_by_numbers_is_the_order_by_names(tmp_path):
    by_name = load_scene(chain_scene(tmp_path / "a.yaml", ("ff", "ff"), "projection", 1, ["u3", "u1", "u2"], 1e-3, 5))
    by_number = load_scene(chain_scene(tmp_path / "b.yaml", ("ff", "ff"), "projection", 1, "gauss-seidel-312", 1e-3, 5))
    assert by_name.scheme == by_number.scheme and by_name.coupling["scheme"] == "gauss-seidel-312"
    assert by_name.scheme_text() == "gauss-seidel-312 (u3 → u1 → u2)"


def test_ten_units_have_dotted_numbers(tmp_path):
    path = chain_scene(tmp_path / "s.yaml", SHAPES[10], "projection", 1, "gauss-seidel-10.9.8.7.6.5.4.3.2.1", 1e-3, 5)
    assert load_scene(path).scheme.order == tuple(range(10, 0, -1))


def test_a_kinematically_driven_unit_at_both_ends(tmp_path):
    """df and fd: the first and the last unit driven by the middle one's acceleration."""
    H, n = 1e-3, 60
    for scheme in ("jacobi", ["u1", "u2", "u3"], ["u3", "u2", "u1"], ["u2", "u1", "u3"]):
        run = run_scene(chain_scene(tmp_path / "s.yaml", ("df", "fd"), "baumgarte", 1, scheme, H, n))
        name = scheme if isinstance(scheme, str) else gs_name(scheme)
        x, v = builtin_run(("df", "fd"), "baumgarte", 1, name, H, n)
        assert relative_difference(run, x, v) < 1e-9, scheme


def _fmu_states(path, history):
    """The FMU run of the scene at ``path`` from the coupling history ``history`` (SI), states ``(n + 1, N, 2)``."""
    scene = load_scene(path)
    c = scene.coupling
    units, couplings = open_units(scene)
    problem = FmuCosimulation(units, couplings, scene.graph(), c["k"], c["H"], perturbation=c["perturbation"])
    try:
        traj = simulate(problem, scene.method, problem.initial_state(), history, scene.n_steps, scheme=scene.scheme)
        return np.array(traj.states)
    finally:
        problem.close()
        for u in units:
            u.close()


def _to_si(chain, history, H):
    """A dimensionless coupling history of the chain in SI: ``lambda = lambda_bar m_ref / H^2``, ``a = a_bar / H^2``."""
    graph = chain.graph()
    scale = np.empty(graph.n_coupling)
    for j, jt in enumerate(graph.joints):
        for v, col in enumerate(graph.columns(j)):
            force = jt.decomposition.variable_kind(v) == "force"
            scale[col] = (chain.reference_mass if force else 1.0) / H**2
    return np.asarray(history) * scale


ORDER_CASES = [
    ("baumgarte", {"index": 1, "mu": 5e-3}, scheme) for scheme in ("jacobi", "gauss-seidel-123", "gauss-seidel-321")
] + [("projection", {}, scheme) for scheme in ("jacobi", "gauss-seidel-123", "gauss-seidel-321")]


@pytest.mark.parametrize("method, params, scheme", ORDER_CASES, ids=lambda v: str(v))
def test_fmu_chain_converges_with_the_builtin_order(tmp_path, method, params, scheme):
    """From the exact start (the coupling history at T_0 ... T_-k too), the largest position error against the
    exact monolithic solution over [0, 0.05 s] falls as the built-in chain's: O(H^(k+1)) for Baumgarte index 1
    and for projection with Gauss-Seidel.  Projection with Jacobi is the built-in model's order on these step
    sizes (its local slopes are still falling, from 3 towards the two-mass study's k + 2 at k = 0)."""
    steps, t_end = np.array([2e-3, 1e-3, 5e-4]), 0.05
    for k in (0, 1, 2):
        err_fmu, err_builtin = [], []
        for H in steps:
            chain = builtin_chain(("ff", "ff"), H)
            problem = chain.problem(k)
            solution = ChainSolution(chain, np.full(3, X0), np.zeros(3))
            state, history = chain_start(problem, solution)
            n = int(round(t_end / H))
            m = engine_method(make_method(method, **params), H)
            builtin = np.array(simulate(problem, m, state, history, n, scheme=scheme).states)[..., 0]
            exact = solution.state(np.arange(n + 1, dtype=float))["x"]
            order = [f"u{i}" for i in scheme[-3:]] if scheme != "jacobi" else "jacobi"
            path = chain_scene(tmp_path / "o.yaml", ("ff", "ff"), method, k, order, H, n, params=params)
            fmu = _fmu_states(path, _to_si(chain, history, H))[..., 0]
            err_fmu.append(np.max(np.abs(fmu - exact)))
            err_builtin.append(np.max(np.abs(builtin - exact)))
        np.testing.assert_allclose(err_fmu, err_builtin, rtol=1e-6, atol=1e-14)  # to the rounding of 0.1 m
        f_fmu, f_builtin = asymptotic_order(steps, err_fmu), asymptotic_order(steps, err_builtin)
        assert abs(f_fmu.order - f_builtin.order) < 0.01
        if method == "baumgarte" or scheme != "jacobi":
            assert f_fmu.status == "asymptotic" and f_fmu.order == pytest.approx(k + 1, abs=0.1), (k, f_fmu)


def _growth(run, steps=100):
    """Growth per macro step of the run's dominant mode: the largest root of the shortest linear recurrence
    ``y_n+p = c_1 y_n+p-1 + ... + c_p y_n`` that the units' positions and velocities follow over the last
    ``steps`` macro steps (least squares over every unit; each equation scaled to its step's size, they are
    homogeneous).  The modes that decayed relative to the dominant ones drop out of it; a complex pair (the
    unstable chains' case) needs p = 2, two pairs close in modulus (the 10 units) p = 4."""
    y = np.concatenate([run.states[..., 0], run.states[..., 1] * (run.times[1] - run.times[0])], axis=1)[-steps:]
    for order in range(1, 7):
        rows = range(len(y) - order)
        size = [np.max(np.abs(y[i + order])) for i in rows]
        A = np.stack([np.concatenate([y[i + m] / w for i, w in zip(rows, size)]) for m in range(order)][::-1], axis=1)
        target = np.concatenate([y[i + order] / w for i, w in zip(rows, size)])
        coef, *_ = np.linalg.lstsq(A, target, rcond=None)
        if np.max(np.abs(A @ coef - target)) < 1e-9:
            return float(np.max(np.abs(np.roots(np.concatenate([[1.0], -coef])))))
    raise AssertionError("the run follows no recurrence of order up to 6: no dominant modes")


@pytest.mark.parametrize(
    "N, method, k, scheme",
    [(3, "baumgarte", 1, ["u3", "u2", "u1"]), (10, "projection", 2, "forward")],
    ids=["3-baumgarte-gs321", "10-projection-gs-forward"],
)
def test_unstable_chain_grows_by_the_spectral_radius(tmp_path, N, method, k, scheme):
    """An unstable configuration of the chain (rho from the built-in chain's family) grows per macro step by rho
    within 1e-3 on the FMU units."""
    H, n = 1e-3, 400
    names = [f"u{i + 1}" for i in range(N)]
    order = names if scheme == "forward" else scheme
    m = engine_method(make_method(method, **PARAMS[method]), H)
    rho = float(spectral_radius_float64(ChainFamily(builtin_chain(SHAPES[N], H), k), m, scheme=gs_name(order))[0])
    assert rho > 1.1
    run = run_scene(chain_scene(tmp_path / "s.yaml", SHAPES[N], method, k, order, H, n))
    growth = _growth(run)
    assert growth == pytest.approx(rho, rel=1e-3)


def test_two_units_with_joints_are_the_two_unit_scene(tmp_path):
    """force_sign in the two formats: the classic scene's 1 and -1 (the coupling force on each unit) is the joint
    format's 1 and 1 (each unit's input the sum of its joints' +-lambda): the same run, bit for bit."""
    classic = chain_scene(tmp_path / "joints.yaml", ("fd",), "baumgarte", 1, "gauss-seidel-21", 1e-3, 40)
    data = yaml.safe_load(classic.read_text())
    assert [s["force_sign"] for s in data["subsystems"].values()] == [1, 1]
    joined = run_scene(classic)
    data["subsystems"]["u2"]["force_sign"] = -1
    data["coupling"]["decomposition"] = data.pop("joints")[0]["decomposition"]
    path = tmp_path / "classic.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    alone = run_scene(path)
    np.testing.assert_array_equal(joined.states, alone.states)
    np.testing.assert_array_equal(joined.coupling, alone.coupling)


def test_the_dataset_names_units_and_joints(capsys, tmp_path):
    path = chain_scene(tmp_path / "s.yaml", SHAPES[10], "baumgarte", 1, "jacobi", 1e-3, 10)
    out = tmp_path / "run.nc"
    assert main(["cosim", str(path), "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert "10 units, joints u1–u2 ff" in summary["described"]
    ds = open_dataset(out)
    assert list(ds["subsystem"].values) == [f"u{i}" for i in range(1, 11)]
    assert ds["position"].dims == ("subsystem", "time") and ds["joint_force"].dims == ("joint", "time")
    assert list(ds["joint_first"].values) == [f"u{i}" for i in range(1, 10)]
    assert list(ds["joint_decomposition"].values) == ["ff"] * 8 + ["fd"]
    assert "multiplier" not in ds and "gap" not in ds
    gap = ds["joint_gap"].values
    assert gap[:, 0].tolist() == [0.0] * 9 and np.max(np.abs(gap)) == summary["max_abs_gap"]
    # ff joints: the force on the first unit is the joint's multiplier; it balances each middle unit's motion
    lam = ds["joint_force"].values[:, 1:]  # (joint, time)
    np.testing.assert_array_equal(lam[0], ds["coupling"].sel(coupling_variable="lambda_c[1]").values[1:])
    m, c, d = (np.array(col)[:, None] for col in zip(*UNITS))
    x, v, a = (ds[key].values[:, 1:] for key in ("position", "velocity", "acceleration"))
    middle = m[1:9] * a[1:9] + c[1:9] * x[1:9] + d[1:9] * v[1:9]  # = -lambda_left + lambda_right
    np.testing.assert_allclose(middle, -lam[:8] + lam[1:9], rtol=1e-9, atol=1e-9 * np.max(np.abs(lam)))
    assert ds.attrs["scheme"] == "jacobi" and ds.attrs["u10_model_name"] == "msd_kinematic"


def test_an_inconsistent_chain_start_is_refused_naming_the_joint_or_projected(capsys, tmp_path):
    x0 = [0.1, 0.12, 0.08]
    path = chain_scene(tmp_path / "s.yaml", ("ff", "ff"), "projection", 1, "jacobi", 1e-3, 10, x0=x0)
    status = main(["cosim", str(path), "--out", str(tmp_path / "run.nc")])
    err = capsys.readouterr().err
    assert status == 2 and "initial: joints[0] (u1–u2, ff): positions differ at t_start: u1 0.1 m, u2 0.12 m" in err
    data = yaml.safe_load(path.read_text()) | {"initial": "project"}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    run = run_scene(path)
    m = np.array([u[0] for u in UNITS[:3]])
    mean = float(m @ x0 / m.sum())  # every unit to the mass-weighted mean: one rigid body
    np.testing.assert_allclose(run.states[0, :, 0], mean, rtol=1e-14)
    assert run.start.position_gap == pytest.approx(0.04)


def test_check_prints_a_table_per_unit_and_the_joints(capsys, tmp_path):
    path = chain_scene(tmp_path / "s.yaml", ("ff", "fd"), "baumgarte", 1, ["u3", "u2", "u1"], 1e-3, 10)
    assert main(["cosim", str(path), "--check"]) == 0
    text = capsys.readouterr().out
    assert "baumgarte, 3 units, joints u1–u2 ff, u2–u3 fd, k = 1, gauss-seidel-321 (u3 → u2 → u1)" in text
    for name in ("u1", "u2", "u3"):
        assert f"  {name}: msd" in text
    assert "every joint's multiplier acts on its two units with opposite signs" in text
    assert "scheme          pass     gauss-seidel-321 (u3 → u2 → u1)" in text
    assert "start           pass" in text and text.strip().endswith("every check passed")
    data = yaml.safe_load(path.read_text())
    data["subsystems"]["u2"]["force_sign"] = -1
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    assert main(["cosim", str(path), "--check"]) == 2
    text = capsys.readouterr().out
    assert "direction       refused" in text and "set subsystems.u2.force_sign: 1" in text


def _edited(tmp_path, edit):
    """The three-unit scene (``ff``, ``ff``; Gauss-Seidel u3, u2, u1) as a dict passed through ``edit``."""
    path = chain_scene(tmp_path / "s.yaml", ("ff", "ff"), "baumgarte", 1, ["u3", "u2", "u1"], 1e-3, 10)
    data = yaml.safe_load(path.read_text())
    edit(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _joint(data, j, **entry):
    data["joints"][j] |= entry


SCHEMA_ERRORS = {
    "unknown subsystem": (
        lambda d: _joint(d, 1, between=["u2", "u4"]),
        ["joints[1].between", "'u4' is not a subsystem", "the subsystems: u1, u2, u3"],
    ),
    "a unit in no joint": (
        lambda d: d["subsystems"].update(u4=dict(d["subsystems"]["u3"])) or d["coupling"]["order"].append("u4"),
        ["joints:", "subsystem u4 takes part in no joint"],
    ),
    "disconnected": (
        lambda d: (
            d["subsystems"].update(u4=dict(d["subsystems"]["u3"]))
            or d["joints"].__setitem__(1, {"between": ["u3", "u4"], "decomposition": "ff"})
            or d["coupling"]["order"].append("u4")
        ),
        ["joints:", "2 separate groups (u1, u2; u3, u4)"],
    ),
    "a loop": (
        lambda d: d["joints"].append({"between": ["u3", "u1"], "decomposition": "ff"}),
        ["joints[2].between", "a loop"],
    ),
    "order misses a unit": (
        lambda d: d["coupling"].update(order=["u3", "u1"]),
        ["coupling.order", "misses u2", "u1, u2, u3"],
    ),
    "order names a stranger": (
        lambda d: d["coupling"].update(order=["u3", "u2", "u9"]),
        ["coupling.order", "'u9' is not a subsystem", "u1, u2, u3"],
    ),
    "order twice": (
        lambda d: d["coupling"].update(order=["u3", "u3", "u1"]),
        ["coupling.order", "names u3 more than once", "u1, u2, u3"],
    ),
    "order without gauss-seidel": (
        lambda d: d["coupling"].update(scheme="jacobi"),
        ["coupling.order", "only with scheme gauss-seidel"],
    ),
    "gauss-seidel without order": (
        lambda d: d["coupling"].pop("order"),
        ["coupling.order", "required with scheme gauss-seidel", "order: [u1, u2, u3]"],
    ),
    "numbered order of too few": (
        lambda d: d["coupling"].pop("order") and d["coupling"].update(scheme="gauss-seidel-21"),
        ["coupling.scheme", "orders 2 subsystems, the scene has 3", "gauss-seidel-123"],
    ),
    "unknown decomposition": (
        lambda d: _joint(d, 0, decomposition="fk"),
        ["joints[0].decomposition", "'fk' is not allowed", "ff, fd, df, dd"],
    ),
    "decomposition in the coupling too": (
        lambda d: d["coupling"].update(decomposition="ff"),
        ["coupling:", "decomposition is not allowed with joints"],
    ),
    "three units without joints": (
        lambda d: d.pop("joints") and d["coupling"].update(decomposition="ff"),
        ["subsystems:", "3 subsystems", "join more by joints"],
    ),
    "a kinematic unit in two joints": (
        lambda d: _joint(d, 0, decomposition="fd"),
        ["joints[0].decomposition", "u2 takes part in joints[1] too", "ff"],
    ),
}


@pytest.mark.parametrize("case", SCHEMA_ERRORS)
def test_a_bad_chain_scene_is_refused_before_any_work(capsys, tmp_path, case):
    """Exit 2, one line naming the file and the key, with the allowed values; no unit is opened, no dataset
    written."""
    edit, needles = SCHEMA_ERRORS[case]
    path = _edited(tmp_path, edit)
    out = tmp_path / "run.nc"
    status = main(["cosim", str(path), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert status == 2 and len(err.splitlines()) == 1 and not out.exists(), err
    assert err.startswith(f"icosim cosim: error: {path}: "), err
    for needle in needles:
        assert needle in err, err


def _scrambled(path, method, k, scheme, H, n):
    """The three units of ``builtin_chain(("df", "ff"))`` written in the file order u2, u3, u1, their joints named
    from the other side: ``[u3, u2]`` ff and ``[u2, u1]`` fd (u1 kinematically driven by u2)."""
    data = yaml.safe_load(chain_scene(path, ("df", "ff"), method, k, scheme, H, n).read_text())
    data["subsystems"] = {name: data["subsystems"][name] for name in ("u2", "u3", "u1")}
    data["joints"] = [
        {"between": ["u3", "u2"], "decomposition": "ff"},
        {"between": ["u2", "u1"], "decomposition": "fd"},
    ]
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.mark.parametrize("scheme", ["jacobi", ["u1", "u2", "u3"], ["u3", "u2", "u1"]], ids=str)
def test_a_chain_in_any_file_order_is_the_same_chain(tmp_path, scheme):
    """Neither the order of the subsystems in the file nor the side a joint names first changes the system: the
    run is the built-in chain's u1, u2, u3 (df, ff), and --predict reports its spectral radius per scheme."""
    H, n, k = 1e-3, 60, 1
    path = _scrambled(tmp_path / "s.yaml", "baumgarte", k, scheme, H, n)
    run = run_scene(path)
    name = scheme if isinstance(scheme, str) else gs_name(scheme)
    x, v = builtin_run(("df", "ff"), "baumgarte", k, name, H, n)
    in_file = [1, 2, 0]  # the file's u2, u3, u1 among u1, u2, u3
    assert relative_difference(run, x[:, in_file], v[:, in_file]) < 1e-9
    answer = predict_scene(load_scene(path))
    family = ChainFamily(builtin_chain(("df", "ff"), H), k)
    method = engine_method(make_method("baumgarte", **PARAMS["baumgarte"]), H)
    assert [row["scene"] for row in answer["schemes"]].count(True) == 1
    for row in answer["schemes"]:
        row_scheme = "jacobi" if row["order"] is None else gs_name(row["order"])
        if row["rho"] is not None:
            rho = float(spectral_radius_float64(family, method, scheme=row_scheme)[0])
            assert row["rho"] == pytest.approx(rho, rel=1e-9), row


@pytest.mark.parametrize("name", ["chain3", "chain10"])
def test_predict_on_the_example_chains_matches_the_parameters_typed_in(capsys, name):
    """The units identified from probing steps are the start values (to 1e-10, as for two units), and every
    scheme's spectral radius is the built-in chain's of those values."""
    path = ROOT / "config" / "scenes" / f"{name}.yaml"
    scene = load_scene(path)
    assert main(["cosim", str(path), "--predict", "--json"]) == 0
    answer = json.loads(capsys.readouterr().out)
    starts = {n: sub["start"] for n, sub in scene.data["subsystems"].items()}
    for unit, start in starts.items():
        for key in ("m", "c", "d"):
            assert answer["units"][unit][key] == pytest.approx(start[key], rel=1e-10)
    names = list(starts)
    joints = scene.data["joints"]
    assert [j["between"] for j in joints] == [[a, b] for a, b in zip(names, names[1:])]  # a row in file order
    chain = Chain(
        tuple(ChainSegment((s["m"],), (s["c"],), (s["d"],)) for s in starts.values()),
        tuple(j["decomposition"] for j in joints),
        scene.coupling["H"],
    )
    family = ChainFamily(chain, scene.coupling["k"])
    assert [row["scene"] for row in answer["schemes"]] == [True] + [False] * (len(answer["schemes"]) - 1)
    assert {row["scheme"] for row in answer["schemes"]} >= {"jacobi", scene.coupling["scheme"]}
    for row in answer["schemes"]:
        rho = float(spectral_radius_float64(family, scene.method, scheme=row["scheme"])[0])
        assert row["rho"] == pytest.approx(rho, rel=1e-9), row
        assert row["verdict"] == ("stable" if rho < 1 else "unstable")
