"""The compiled links' integrator (icosim.problems.pendulum.integrator.compiled) against the numpy reference (tests/reference_radau.py).

The kernel and ``radau_batch`` are the same algorithm (scipy's Radau, batched) for the links'
right-hand sides: the step sequence and the work counters must be the same, the numbers
equal up to round-off (matrix inverses, sin/cos and the order of the sums
over a state's components may differ in the last bits).
"""

import json

import numpy as np
import pytest
import yaml
from reference_links import NumpyLink1, NumpyLink2
from reference_radau import NumpyPendulum, fd_jacobian, radau_batch

from icosim import make_method
from icosim.problems.pendulum import runs
from icosim.problems.pendulum.integrator.compiled_algebra import all_finite, inverse, nan_maximum
from icosim.problems.pendulum.integrator.systems import CompiledLink, IntegrationError
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.runs import run_cosimulation
from icosim.studies.trade.measures import check_scheme

P = PendulumParameters()
STATE = P.initial_state()


def _counters(r):
    return r.n_steps, r.n_rejected, r.n_fev, r.n_jev


def _problem(L, kind, B, K, seed):
    """A link, a batch of B states near the initial one and random input polynomials with K coefficients."""
    rng = np.random.default_rng(seed)
    link = L(P, kind)
    y = STATE[:2] if L is NumpyLink1 else STATE[2:]
    y0 = y + 0.01 * rng.standard_normal((B, link.n))
    coef = 5 * rng.standard_normal((B, K, 2))
    return link, y0, coef


@pytest.mark.parametrize("L", [NumpyLink1, NumpyLink2])
@pytest.mark.parametrize("kind", ["force", "kinematic"])
@pytest.mark.parametrize("B", [1, 3])
@pytest.mark.parametrize("K", [1, 2, 4])
def test_one_macro_step_matches_radau_batch(L, kind, B, K):
    """A macro step as the co-simulation takes it (H = 1e-3, shared first Jacobian): the same Jacobian,
    end state and derivative up to a few ulp, and the same counters."""
    link, y0, coef = _problem(L, kind, B, K, seed=K)
    H = 1e-3
    fun = link.rhs(coef, H)
    jac0 = fd_jacobian(fun, 0.0, y0[:1], fun(0.0, y0[:1]))[0]
    kernel = CompiledLink(link)
    jac0_compiled = kernel.fd_jacobian(coef[:1], H, 0.0, y0[:1])[0]
    # forward differences divide a round-off difference of sin/cos by sqrt(eps): a few 1e-8 relative at worst
    np.testing.assert_allclose(jac0_compiled, jac0, rtol=1e-7, atol=1e-7)
    ref = radau_batch(fun, 0.0, H, y0, jac0=jac0)
    got = kernel.radau(coef, H, 0.0, H, y0, jac0=jac0)
    assert _counters(got) == _counters(ref)
    np.testing.assert_allclose(got.y, ref.y, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(got.f, ref.f, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("L", [NumpyLink1, NumpyLink2])
@pytest.mark.parametrize("kind", ["force", "kinematic"])
@pytest.mark.parametrize("B", [1, 3])
def test_many_steps_with_rejections_match_radau_batch(L, kind, B):
    """One long interval with tight tolerances (over a hundred steps, rejected ones among them, fresh
    Jacobians after failed Newton iterations): the same step sequence, the end states equal to 1e-12."""
    link, y0, coef = _problem(L, kind, B, 3, seed=B)
    H, tol = 0.3, 1e-10
    ref = radau_batch(link.rhs(coef, H), 0.0, H, y0, rtol=tol, atol=tol)  # no jac0: the first Jacobian too
    got = CompiledLink(link).radau(coef, H, 0.0, H, y0, rtol=tol, atol=tol)
    assert ref.n_steps > 40 and ref.n_rejected > 0
    assert _counters(got) == _counters(ref)
    # over ~100-250 steps round-off accumulates (1e-13 relative at most seen); far below the tolerance
    np.testing.assert_allclose(got.y, ref.y, rtol=1e-12, atol=1e-14)
    assert got.h_next == pytest.approx(ref.h_next, rel=1e-6)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy's overflow in the input polynomial
def test_errors_are_radau_batch_errors():
    """The kernel's error codes come back as radau_batch's exceptions, with the same messages."""
    link, y0, coef = _problem(NumpyLink2, "force", 1, 2, seed=0)
    kernel = CompiledLink(link)
    with pytest.raises(IntegrationError, match="more than 3 steps") as got:
        kernel.radau(coef, 0.3, 0.0, 0.3, y0, rtol=1e-10, atol=1e-10, max_steps=3)
    with pytest.raises(IntegrationError) as ref:
        radau_batch(link.rhs(coef, 0.3), 0.0, 0.3, y0, rtol=1e-10, atol=1e-10, max_steps=3)
    assert str(got.value) == str(ref.value)
    huge = np.full_like(coef, 1e308)  # the input overflows: derivative not finite at the end of the first step
    with pytest.raises(IntegrationError) as got:
        kernel.radau(huge, 1e-3, 0.0, 1e-3, y0, jac0=np.eye(6))
    with pytest.raises(IntegrationError) as ref:
        radau_batch(link.rhs(huge, 1e-3), 0.0, 1e-3, y0, jac0=np.eye(6))
    assert str(got.value) == str(ref.value)
    with pytest.raises(ValueError, match="rtol"):
        kernel.radau(coef, 1e-3, 0.0, 1e-3, y0, rtol=0.0)


def test_a_link_at_rest_integrates_with_zero_error_estimates():
    """Link 1 driven kinematically by a zero input, at rest: its derivative and every error estimate are
    exactly 0.  Both paths integrate it (before, 0.0 ** -0.25 raised ZeroDivisionError): the state stays
    0, the first step spans the interval (a zero derivative sets no scale), and the next step is
    MAX_FACTOR times longer, as scipy's Radau grows a step whose error is 0; counters and next step agree."""
    from icosim.problems.pendulum.integrator.tableau import MAX_FACTOR

    link = NumpyLink1(P, "kinematic")
    coef, y0, H = np.zeros((1, 2, 2)), np.zeros((1, 2)), 1e-3
    ref = radau_batch(link.rhs(coef, H), 0.0, H, y0)
    got = CompiledLink(link).radau(coef, H, 0.0, H, y0)
    assert np.all(ref.y == 0) and np.all(got.y == 0)
    assert (got.n_steps, got.n_rejected, got.n_fev, got.n_jev) == (ref.n_steps, ref.n_rejected, ref.n_fev, ref.n_jev)
    assert ref.n_steps == 1 and ref.n_rejected == 0
    assert got.h_next == ref.h_next == MAX_FACTOR * H


@pytest.mark.parametrize("tol", [1e-4, 1e-8, 1e-12])
def test_the_monolithic_pendulum_matches_radau_batch(tol):
    """The monolithic baseline (the whole pendulum through the links' kernel, every accepted step recorded)
    against radau_batch on Monolithic.rhs over 1 s: the right-hand side bitwise (the same expressions in the
    same order), the same counters, end states within 1e-13 and step times within 1e-8 s (the step-size
    controller feeds on an error estimate that round-off moves in its last digits)."""
    from icosim.problems.pendulum.integrator.compiled_links import MONOLITHIC, member_rhs, monolithic_parameters
    from icosim.problems.pendulum.integrator.systems import monolithic_radau
    from icosim.problems.pendulum.reference import Monolithic

    mono = Monolithic(P)
    y0 = mono.initial_state()
    par, out = monolithic_parameters(P), np.empty(4)
    for y in np.random.default_rng(0).standard_normal((20, 4)):
        member_rhs(MONOLITHIC, 0, par, 1.0, 0.0, y, np.zeros((1, 2)), out)
        np.testing.assert_array_equal(out, mono.rhs(0.0, y))
    ref = radau_batch(mono.rhs, 0.0, 1.0, y0, rtol=tol, atol=tol, record_steps=True)
    got = monolithic_radau(P, 0.0, 1.0, y0, rtol=tol, atol=tol, record_steps=True)
    assert _counters(got) == _counters(ref)
    assert got.t_steps.shape == ref.t_steps.shape and got.y_steps.shape == ref.y_steps.shape
    assert got.t_steps[0] == 0.0 and got.t_steps[-1] == 1.0
    np.testing.assert_array_equal(got.y_steps[-1], got.y)
    np.testing.assert_allclose(got.y, ref.y, rtol=0, atol=1e-13)
    np.testing.assert_allclose(got.t_steps, ref.t_steps, rtol=0, atol=1e-8)
    assert monolithic_radau(P, 0.0, 1.0, y0, rtol=tol, atol=tol).t_steps is None


def _both_paths(monkeypatch, method, kw, dec, k, t_end, scheme="jacobi"):
    """The run on the numpy reference (NumpyPendulum) and on the package's compiled problem."""
    results = []
    for problem in (NumpyPendulum, runs.PendulumCosimulation):
        with monkeypatch.context() as m:
            m.setattr(runs, "PendulumCosimulation", problem)
            results.append(
                run_cosimulation(P, make_method(method, **kw), dec, k, H=1e-3, t_end=t_end, scheme=check_scheme(scheme))
            )
    return tuple(results)


BAUMGARTE = dict(index=1, mu=1e-3)
WEIGHTED = dict(index=1, a=1.0, b=1.0)


@pytest.mark.parametrize(
    "method, kw, dec, k, scheme, t_end, state_tol, force_tol",
    [
        # seen: states 6e-16, forces 4e-11; the forces come from forward differences (step 1e-3) through the
        # coupling solve, and the numpy path itself moves them by 8e-11 for a 1-ulp change of phi1_0
        ("baumgarte", BAUMGARTE, "ff", 1, "jacobi", 0.1, 1e-13, 1e-9),
        ("projection", {}, "dd", 1, "jacobi", 0.1, 1e-13, 1e-12),  # seen: 6e-16, 4e-15
        # the weighted multiplier at k = 2 grows by ~1.13 per step and round-off with it (seen: 2e-8, 2e-3
        # relative in the oscillating force); a 1-ulp change of phi1_0 moves the numpy path ~50 times more
        ("weighted", WEIGHTED, "ff", 2, "jacobi", 0.18, 1e-6, 2e-2),
        ("baumgarte", BAUMGARTE, "fd", 1, "gauss-seidel-12", 0.03, 1e-10, 1e-5),  # seen: 1e-12, 2e-7
    ],
)
def test_runs_match_the_numpy_path(monkeypatch, method, kw, dec, k, scheme, t_end, state_tol, force_tol):
    """Whole co-simulation runs: the same outcome and work counters, the series equal up to amplified
    round-off (angles and constraints absolutely, joint forces relative to max(1, their largest value))."""
    ref, got = _both_paths(monkeypatch, method, kw, dec, k, t_end, scheme)
    assert (got.status, got.reason) == (ref.status, ref.reason) == ("stable", "")
    assert got.stats == ref.stats and got.jacobian_stats == ref.jacobian_stats
    assert got.t.size == ref.t.size == round(t_end / 1e-3) + 1
    for name, values in ref.series.items():
        tol = force_tol * max(1.0, np.max(np.abs(values))) if name.startswith("lambda") else state_tol
        np.testing.assert_allclose(got.series[name], values, rtol=0, atol=tol, err_msg=name)


def test_a_diverging_run_diverges_at_the_same_step(monkeypatch):
    """weighted ff k = 2 diverges at 0.205 s on both paths.  In the last steps of the blow-up round-off
    has grown to ~1e-7 and may move one borderline step-size decision: the step counts stay equal, the
    right-hand side evaluations within a few (a 1-ulp change of phi1_0 moves the numpy path by ~50)."""
    ref, got = _both_paths(monkeypatch, "weighted", WEIGHTED, "ff", 2, 0.25)
    assert ref.status == got.status == "diverged"
    assert got.t_diverged == ref.t_diverged and got.reason == ref.reason
    for key in ("integrations", "steps", "rejected", "split", "macro_steps"):
        assert got.stats[key] == ref.stats[key], key
    assert abs(got.stats["fev"] - ref.stats["fev"]) <= 3
    np.testing.assert_allclose(got.series["phi1"], ref.series["phi1"], rtol=0, atol=1e-5)


# -- the dense algebra the kernel uses instead of numba's LAPACK bindings ----------------------------
@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
@pytest.mark.parametrize("n", [1, 2, 3, 6])
def test_inverse_is_numpys_inverse(n, dtype):
    """LU with partial pivoting against np.linalg.inv (LAPACK gesv): Newton-like matrices mu I - J and
    matrices whose pivots need row interchanges (a zero on the diagonal)."""
    rng = np.random.default_rng(n)
    for trial in range(20):
        J = rng.standard_normal((n, n)) * 10.0 ** rng.uniform(-3, 3)
        mu = (3.6 + 1.2j if dtype is np.complex128 else 3.6) * 10.0 ** rng.uniform(-2, 4)
        M = (mu * np.eye(n) - J).astype(dtype)
        if trial % 2 and n > 1:
            M[0, 0] = 0.0  # the first pivot must come from another row
        out = np.empty((n, n), dtype)
        assert inverse(M, out)
        want = np.linalg.inv(M)
        scale = np.abs(want).max()
        np.testing.assert_allclose(out, want, rtol=0, atol=1e-12 * scale * np.linalg.cond(M))
        np.testing.assert_allclose(M @ out, np.eye(n), rtol=0, atol=1e-12 * np.linalg.cond(M))


@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
def test_inverse_reports_an_exactly_singular_matrix(dtype):
    """A zero pivot is what makes gesv raise LinAlgError (radau_batch: 'singular Newton matrix')."""
    M = np.array([[1.0, 2.0], [2.0, 4.0]], dtype)
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.inv(M)
    assert not inverse(M, np.empty((2, 2), dtype))
    assert not inverse(np.zeros((3, 3), dtype), np.empty((3, 3), dtype))


def test_nan_maximum_and_all_finite_are_numpys():
    values = [0.0, -1.0, 2.5, np.inf, -np.inf, np.nan]
    for a in values:
        for b in values:
            np.testing.assert_equal(nan_maximum(a, b), np.maximum(a, b))
    for x in ([1.0, 2.0], [1.0, np.nan], [np.inf], [1 + 1j, complex(0, np.nan)], [1 + 1j]):
        x = np.array(x)
        assert all_finite(x) == np.all(np.isfinite(x))


def test_warm_up_compiles_the_signature_the_runs_use():
    """warm_up's arguments have the types the wrapper passes: a run after it compiles nothing more,
    so nothing of numba's compilation falls inside a run's timed region."""
    from icosim.problems.pendulum.integrator import compiled

    compiled.warm_up()
    for L in (NumpyLink1, NumpyLink2):
        link, y0, coef = _problem(L, "force", 2, 3, seed=0)
        kernel = CompiledLink(link)
        kernel.radau(coef, 1e-3, 0.0, 1e-3, y0, jac0=kernel.fd_jacobian(coef[:1], 1e-3, 0.0, y0[:1])[0])
    assert len(compiled._radau.signatures) == 1
    assert len(compiled._jacobian.signatures) == 1


def test_compile_record_lists_what_the_runs_use_in_strict_json():
    """The workflow's compile job records numba's version and the one signature per kernel that a run
    then uses (nothing compiled later), with cache hits + misses = 1 per kernel in a fresh process."""
    import subprocess
    import sys

    code = (
        "import json\n"
        "from icosim.io.jsonio import dumps\n"
        "from icosim.problems.pendulum.integrator.compiled_step import compile_kernels\n"
        "print(dumps(compile_kernels()))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    record = json.loads(out.stdout)
    from icosim.problems.pendulum.integrator import compiled, compiled_step

    compiled_step.warm_up()
    # a Gauss-Seidel run: every entry point (the leading link's outputs re-evaluated: _link_outputs)
    run_cosimulation(P, make_method("baumgarte", **BAUMGARTE), "fd", 1, H=1e-3, t_end=2e-3, scheme="gauss-seidel-12")
    assert record["numba"] == compiled.numba.__version__
    assert set(record["kernels"]) == {"_jacobian", "_radau", "_link_step", "_link_outputs"}
    for name, kernel in record["kernels"].items():
        module = compiled if hasattr(compiled, name) else compiled_step
        assert kernel["signatures"] == [str(s) for s in getattr(module, name).signatures]
        assert kernel["cache_hits"] + kernel["cache_misses"] == 1
    assert record["cpu_seconds"] > 0 and record["wall_seconds"] > 0


def test_every_job_that_runs_the_integrator_waits_for_the_one_compile_job(tmp_path):
    """In the DAG of the full workflow: one pendulum_kernels job, and an edge from it to every job of
    the rules whose scripts run co-simulations, listed here (two runs starting together on a cold cache
    would each compile), and to no other (the figures, merges and report never integrate)."""
    import re

    from helpers import ROOT, copy_workflow, snakemake

    # pendulum_run runs every scheme of pendulum.schemes (Jacobi and Gauss-Seidel) of its (method, decomposition);
    # an FMU scene checked against the built-in pendulum (config/fmi.yaml) runs it too
    # pendulum_baselines integrates the monolithic pendulum with it
    runners = {"pendulum_run", "pendulum_trade_group", "pendulum_tolerance", "pendulum_adaptive", "pendulum_baselines"}
    fmi = yaml.safe_load((ROOT / "config" / "fmi.yaml").read_text())["fmi"]["scenes"]
    pendulum_scenes = {name for name, scene in fmi.items() if scene["builtin"] == "pendulum"}
    assert pendulum_scenes and len(pendulum_scenes) < len(fmi)
    dag = snakemake(copy_workflow(tmp_path), "--dag").stdout
    labels = dict(re.findall(r'^\s*(\d+)\[label = "(\w+)', dag, flags=re.M))
    scenes = dict(re.findall(r'^\s*(\d+)\[label = "fmi_scene\\nscene: (\w+)', dag, flags=re.M))
    edges = re.findall(r"^\s*(\d+) -> (\d+)", dag, flags=re.M)
    kernels = [i for i, rule in labels.items() if rule == "pendulum_kernels"]
    assert len(kernels) == 1
    fed = {b for a, b in edges if a == kernels[0]}
    assert {labels[b] for b in fed} == runners | {"fmi_scene"}
    jobs = [i for i, rule in labels.items() if rule in runners]
    assert jobs and set(jobs) <= fed
    assert len(scenes) == len(fmi) and {scenes[i] for i in fed if i in scenes} == pendulum_scenes
    # as ancient(): a rerun of the compile job (an edited script, -R, a deleted record) reruns no run
    rules = "".join(f.read_text() for f in sorted((tmp_path / "workflow" / "rules").glob("*.smk")))
    uses = re.findall(r"kernels=(.*),", rules)
    assert len(uses) == len(runners) + 1 and all("ancient(PENDULUM_KERNELS)" in use for use in uses)


def test_an_edited_source_the_kernels_inline_recompiles_them(tmp_path):
    """numba alone would load kernels compiled from an old compiled_links.py (its cache is keyed on
    compiled.py's time stamp only): on a copy of the package with the checkout's cache of the kernels
    (files and time stamps as they are), a process loads the cache, and after an edit of
    compiled_links.py the next compiles again; so does the one after an edit of compiled.py, which the
    kernels of compiled_step.py inline.  Where the checkout keeps no cache beside the package, a first
    process on the copy compiles and the second loads."""
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    from helpers import ROOT

    from icosim.problems.pendulum.integrator import compiled_step

    compiled_step.warm_up()  # the checkout's cache holds the kernels (written now, or loaded as the tests above did)
    src = ROOT / "src"
    shutil.copytree(src, tmp_path / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    package = tmp_path / "src" / "icosim" / "problems" / "pendulum" / "integrator"
    cache = Path(compiled_step.__file__).parent / "__pycache__"
    seed = [p for p in cache.iterdir() if p.suffix in (".nbi", ".nbc", ".sources")] if cache.is_dir() else []
    if all(list(cache.glob(f"{kernel}-*.nbi")) for kernel in ("compiled._radau", "compiled_step._link_step")):
        (package / "__pycache__").mkdir()
        for path in seed:
            shutil.copy2(path, package / "__pycache__" / path.name)
    else:
        seed = []
    code = "import json\nfrom icosim.problems.pendulum.integrator.compiled_step import compile_kernels\nprint(json.dumps(compile_kernels()))\n"
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "src"), "OPENBLAS_NUM_THREADS": "1"}

    def caches():
        """(hits, misses) of the integrator and of the macro-step kernel that inlines it (compiled_step.py)."""
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
        kernels = json.loads(out.stdout)["kernels"]
        return [(kernels[name]["cache_hits"], kernels[name]["cache_misses"]) for name in ("_radau", "_link_step")]

    if not seed:
        assert caches() == [(0, 1), (0, 1)]
    assert caches() == [(1, 0), (1, 0)]
    links = package / "compiled_links.py"
    links.write_text(links.read_text() + "\n# an edit\n")
    assert caches() == [(0, 1), (0, 1)]
    # compiled.py's own time stamp keys its cache (numba), its digest that of the kernels inlining it
    integrator = package / "compiled.py"
    integrator.write_text(integrator.read_text() + "\n# an edit\n")
    assert caches() == [(0, 1), (0, 1)]
