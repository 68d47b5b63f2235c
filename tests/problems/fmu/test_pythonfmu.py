"""A second exporter: the force-driven unit written in Python and exported with pythonfmu (fmus/python), coupled
with the C unit, as one of a pair and as the middle unit of a 3-unit chain.  It cannot interpolate inputs, so it
gets the coupling polynomial as sub-steps: the run follows the built-in model (the pair's, the chain's) to second
order in the sub-step."""

import os
import re
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import yaml
from helpers import ROOT

from icosim.engine.methods import engine_method, make_method
from icosim.engine.run import simulate
from icosim.problems.fmu.run import run_scene
from icosim.problems.linear.model import PhysicalModel
from icosim.problems.linear.problem import LinearCosimulation

pytestmark = pytest.mark.fmu

SCENE = ROOT / "config" / "scenes" / "two_mass_python.yaml"


@pytest.fixture(autouse=True, scope="module")
def pythonfmu():
    """The Python unit is exported with pythonfmu (the fmi extra)."""
    return pytest.importorskip("pythonfmu", reason="the Python unit is exported with pythonfmu (the fmi extra)")


def builtin(data, e0):
    """The built-in model's positions from the same start: the positions, and the coupling force ``e0`` (N) the
    FMU run started with."""
    c = data["coupling"]
    H, n = c["H"], round(data["t_end"] / c["H"])
    s1, s2 = (data["subsystems"][b]["start"] for b in ("body1", "body2"))
    model = PhysicalModel(m1=s1["m"], m2=s2["m"], c1=s1["c"], c2=s2["c"], d1=s1["d"], d2=s2["d"], H=H)
    problem = LinearCosimulation(model.coefficients(), c["decomposition"], c["k"])
    method = engine_method(make_method(c["method"], index=c["index"], a=c["a"], b=c["b"]), H)
    state = np.array([[s1["x0"], 0.0], [s2["x0"], 0.0]])
    history = np.full((c["k"] + 1, 1), float(e0[0]) * H**2 / s1["m"])  # lambda_bar = lambda H^2 / m1
    traj = simulate(problem, method, state, history, n, scheme=c["scheme"])
    return np.array(traj.states)[..., 0]


def run_with(tmp_path, substeps):
    data = yaml.safe_load(SCENE.read_text())
    data["coupling"]["substeps"] = substeps
    data["t_end"] = 0.1
    for sub in data["subsystems"].values():
        sub["fmu"] = str((SCENE.parent / sub["fmu"]).resolve())
    path = tmp_path / f"python_{substeps}.yaml"
    path.write_text(yaml.safe_dump(data))
    return data, run_scene(path)


def test_pythonfmu_unit_follows_the_builtin_model_to_second_order_in_the_sub_step(tmp_path):
    errors = []
    for substeps in (8, 16):
        data, run = run_with(tmp_path, substeps)
        assert run.units["body1"]["generation_tool"].startswith("PythonFMU")
        assert run.units["body1"]["inputs"] == f"substeps ({substeps})"
        assert run.units["body2"]["inputs"] == "derivatives"
        x = builtin(data, run.coupling[0])
        errors.append(np.max(np.abs(run.states[..., 0] - x)) / np.max(np.abs(x)))
    assert errors[1] < 1e-4
    assert 3 < errors[0] / errors[1] < 5


CHAIN_UNITS = [(1.0, 1000.0, 2.0), (2.0, 500.0, 1.0), (0.5, 2000.0, 0.5)]  # m, c, d of a, b, c


def python_chain(path, scheme, substeps):
    """Three units in a row joined by two ff joints, the middle one the pythonfmu unit (its force input the
    sum of the two joints' multipliers), the ends the C unit; Baumgarte index 1, k = 1, 0.1 s."""
    names = ("a", "b", "c")
    subsystems = {}
    for name, (m, c, d) in zip(names, CHAIN_UNITS):
        python = name == "b"
        subsystems[name] = {
            "fmu": str(ROOT / "fmus" / ("python/msd_python.py" if python else "msd")),
            "start": {"m": m, "c": c, "d": d, "x0": 0.1},
            "position": "x", "velocity": "v", "acceleration": "a", "force": "lam" if python else "lambda",
            "force_sign": 1,
        }  # fmt: skip
    coupling = {"method": "baumgarte", "index": 1, "mu": 1e-2, "k": 1, "H": 1e-3, "substeps": substeps}
    coupling |= {"scheme": "jacobi"} if scheme == "jacobi" else {"scheme": "gauss-seidel", "order": list(scheme)}
    data = {
        "subsystems": subsystems,
        "joints": [{"between": ["a", "b"], "decomposition": "ff"}, {"between": ["b", "c"], "decomposition": "ff"}],
        "coupling": coupling,
        "t_end": 0.1,
        "initial_coupling": [0.0, 0.0],
    }
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.mark.parametrize("scheme", ["jacobi", ("a", "b", "c"), ("c", "b", "a")], ids=str)
def test_a_chain_with_the_pythonfmu_unit_in_the_middle_follows_the_builtin_chain(tmp_path, scheme):
    """The middle unit of a 3-unit chain exported by pythonfmu (two joints reach its one force input), the ends
    the C unit: the run follows the built-in chain (icosim.problems.linear.chain) from the same start, to second
    order in the Python unit's sub-step, under Jacobi and two Gauss-Seidel orders."""
    from icosim.problems.linear.chain import Chain, ChainSegment

    H, n = 1e-3, 100
    chain = Chain(tuple(ChainSegment((m,), (c,), (d,)) for m, c, d in CHAIN_UNITS), ("ff", "ff"), H)
    problem = chain.problem(1)
    method = engine_method(make_method("baumgarte", index=1, mu=1e-2), H)
    name = scheme if scheme == "jacobi" else "gauss-seidel-" + "".join(str("abc".index(u) + 1) for u in scheme)
    start, history = np.array([[0.1, 0.0]] * 3), np.zeros((2, problem.n_coupling))
    x = np.array(simulate(problem, method, start, history, n, scheme=name).states)[..., 0]
    errors = []
    for substeps in (8, 16):
        run = run_scene(python_chain(tmp_path / f"chain_{substeps}.yaml", scheme, substeps))
        assert run.status == "completed"
        assert run.units["b"]["generation_tool"].startswith("PythonFMU")
        assert run.units["b"]["inputs"] == f"substeps ({substeps})" and run.units["a"]["inputs"] == "derivatives"
        errors.append(np.max(np.abs(run.states[..., 0] - x)) / np.max(np.abs(x)))
    assert errors[1] < 1e-4
    assert 3 < errors[0] / errors[1] < 5


def test_nonlinear_scene_converges_as_the_macro_step_shrinks(tmp_path):
    """The Python unit with a cubic spring (config/scenes/duffing_python.yaml: Baumgarte index 1, k = 2, two
    corrector passes): the end position converges as H halves (the error falls by more than 4 each time) and
    the joint holds ever better."""
    scene = ROOT / "config" / "scenes" / "duffing_python.yaml"
    ends, gaps = {}, {}
    for H in (2e-3, 1e-3, 5e-4, 2.5e-4):
        data = yaml.safe_load(scene.read_text())
        for sub in data["subsystems"].values():
            sub["fmu"] = str((scene.parent / sub["fmu"]).resolve())
        data["coupling"] |= {"H": H, "mu": H, "substeps": 32}
        data["t_end"] = 0.05
        path = tmp_path / f"duffing_{H:g}.yaml"
        path.write_text(yaml.safe_dump(data))
        run = run_scene(path)
        assert run.status == "completed"
        ends[H], gaps[H] = run.states[-1, 0, 0], abs(run.states[-1, 0, 0] - run.states[-1, 1, 0])
    errors = [abs(ends[H] - ends[2.5e-4]) for H in (2e-3, 1e-3, 5e-4)]
    assert errors[0] > 4 * errors[1] > 16 * errors[2] > 0
    assert gaps[2.5e-4] < gaps[2e-3]


def test_a_unit_that_fails_fatally_stops_the_run_cleanly(capsys, tmp_path):
    """Baumgarte index 2 at k = 2 is unstable here: the Python unit's state overflows, its step raises and
    pythonfmu returns fmi2Fatal.  The run stops naming the unit, the step and the time, and no FMI function is
    called on the unit afterwards (the standard allows none; calling one crashed the process)."""
    from icosim.cli import main

    scene = ROOT / "config" / "scenes" / "duffing_python.yaml"
    data = yaml.safe_load(scene.read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str((scene.parent / sub["fmu"]).resolve())
    data["coupling"] |= {"index": 2, "iterations": 1}
    data["t_end"] = 0.05
    path = tmp_path / "fatal.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "run.nc"
    assert main(["cosim", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "unit body1 refused macro step" in err and "(doStep returned fatal)" in err
    assert not out.exists()


# A workflow job's process with pythonfmu units: a scene run (its units opened and closed), then one unit left open.
EXITING_JOB = textwrap.dedent(
    """
    import sys
    from icosim.problems.fmu.run import run_scene
    from icosim.problems.fmu.units import Unit
    run = run_scene(sys.argv[1])
    Unit("left_open", run.units["body1"]["fmu"], {"position": "x"}, {})  # closed by no one
    print(run.status)
    """
)


def library_errors(log: str) -> list:
    """valgrind's errors whose own stack (not where the block was allocated or freed) is in a unit's library."""
    errors, block = [], []
    for line in log.splitlines() + [""]:
        text = re.sub(r"^==\d+== ?", "", line)
        if text.strip():
            block.append(text)
            continue
        own = []
        for entry in block:
            if entry.lstrip().startswith(("Address ", "Block was")):
                break
            own.append(entry)
        if any("/binaries/linux64/" in entry for entry in own):
            errors.append("\n".join(own[:4]))
        block = []
    return errors


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("valgrind") is None, reason="needs valgrind (memcheck)")
def test_a_process_that_ran_pythonfmu_units_exits_without_touching_freed_memory(tmp_path):
    """pythonfmu frees its library's interpreter state twice at exit, unless icosim released it before
    (icosim.problems.fmu.pythonfmu): the freed block written to, which glibc reported as "corrupted
    double-linked list" in some runs (docs/fmi.md).  memcheck sees it in every run: the process exits cleanly and
    the units' libraries read or write no freed memory, the unit left open included."""
    from icosim.problems.fmu.build import build_unit

    for source in ("python/msd_python.py", "msd"):  # built here, not under memcheck
        build_unit(ROOT / "fmus" / source)
    data = yaml.safe_load(SCENE.read_text())
    for sub in data["subsystems"].values():
        sub["fmu"] = str((SCENE.parent / sub["fmu"]).resolve())
    data["t_end"] = 0.01
    scene = tmp_path / "short.yaml"
    scene.write_text(yaml.safe_dump(data))
    log = tmp_path / "memcheck.log"
    proc = subprocess.run(
        ["valgrind", "--undef-value-errors=no", "--num-callers=12", f"--log-file={log}"]
        + [sys.executable, "-c", EXITING_JOB, str(scene)],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONMALLOC": "malloc"},  # every object through malloc, where memcheck sees it
        timeout=300,
    )
    assert proc.returncode == 0 and "corrupted" not in proc.stderr, proc.stderr[-2000:]
    assert proc.stdout.split() == ["completed"]
    assert library_errors(log.read_text()) == []
