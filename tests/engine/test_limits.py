"""Reliability at the extremes (icosim.engine.bounds, icosim rho, the grid API, the datasets' integrity).

Every input once found hanging, crashing or printing different answers at different
precisions now finishes quickly with exit 0 (an answer, possibly ``undecided`` with the
reason) or 2 (bad input, one line naming the limit or argument), prints strict JSON, and
gives the same verdict at every precision.  The expected verdicts come from the proofs
themselves checked against 60-digit mpmath values or theory, never from the code's own
earlier output.
"""

from __future__ import annotations

import functools
import json
import os
import resource
import subprocess
import sys
import time
from fractions import Fraction

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from icosim import TestModel, make_method
from icosim.cli import main
from icosim.engine.bounds import MAX_DIGITS, MAX_K, time_budget
from icosim.errors import PointTimeout
from icosim.io.integrity import quarantine_corrupt, remove_stale_parts, sidecar, verify
from icosim.problems.linear.spectral import spectral_radius, spectral_radius_mp

WEIGHTED = ["--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff", "--k", "2"]
ONES = ["--am21", "1", "--alr21", "1", "--ali21", "1"]
GIB = 1 << 30


def strict_loads(text: str):
    """json.loads that refuses NaN and Infinity (what a strict parser does)."""

    def refuse(name):
        raise ValueError(f"non-strict JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


def run_cli(args, *, seconds=60):
    """``icosim`` in a fresh process under a 6 GiB address-space limit: (exit code, stdout, stderr, seconds)."""

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (6 * GIB, 6 * GIB))

    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    code = "import sys; from icosim.cli import main; sys.exit(main())"
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        timeout=seconds,
        preexec_fn=limit,
        env=env,
    )
    return proc.returncode, proc.stdout, proc.stderr, time.perf_counter() - t0


# -- the inputs once measured hanging or crashing ------------------------------------------------------


@pytest.mark.parametrize(
    "args,code,expect",
    [
        # a guard precision beyond the cap: undecided with the reason, at once
        (WEIGHTED + ["--lr1=-1e6", "--li1", "0.05", *ONES], 0, "guard bits"),
        (WEIGHTED[:-1] + ["100", "--lr1", "-0.05", "--li1", "0.05", *ONES], 2, f"0..{MAX_K}"),
        (WEIGHTED[:-1] + ["100000", "--lr1", "-0.05", "--li1", "0.05", *ONES], 2, f"0..{MAX_K}"),
        (WEIGHTED + ["--lr1", "-0.05", "--li1", "0.05", *ONES, "--digits", "1000000000"], 2, str(MAX_DIGITS)),
        (WEIGHTED + ["--lr1", "-0.05", "--li1", "0.05", *ONES, "--digits", "1000000000000000000"], 2, str(MAX_DIGITS)),
        # derived quantities that overflow float64: refused, naming the input responsible
        (
            ["--method", "baumgarte", "--index", "1", "--mu", "1e160", "--decomposition", "ff", "--k", "1"]
            + ["--lr1", "-0.05", "--li1", "0.05", *ONES],
            2,
            "argument --mu: mu = 1e+160 makes gamma",
        ),
        (
            WEIGHTED + ["--lr1", "-0.05", "--li1", "0", "--am21", "1", "--alr21", "1e200", "--ali21", "1"],
            2,
            "argument --alr21",
        ),
        (
            WEIGHTED + ["--lr1=-0.05", "--li1", "0.05", "--am21", "1", "--alr21", "1", "--ali21", "1e300"],
            2,
            "argument --ali21",
        ),
        # a rotation of ~5e148 per step: no precision up to the cap resolves it -- undecided, not a number
        (WEIGHTED + ["--lr1=-0.05", "--li1", "0.05", "--am21", "1", "--alr21", "1", "--ali21", "1e150"], 0, "singular"),
    ],
)
def test_extreme_inputs_finish_with_an_answer_or_a_clear_error(args, code, expect):
    rc, out, err, seconds = run_cli(["rho", *args, "--json"])
    assert rc == code and seconds < 60, (rc, out, err)
    assert "Traceback" not in err
    if code == 2:
        assert err.strip().splitlines()[-1].startswith("icosim rho: error: argument") and expect in err
    else:
        answer = strict_loads(out)
        assert answer["verdict"] == "undecided" and answer["rho"] is None and expect in answer["reason"]


def test_the_point_1e_minus_9_above_1_is_unstable_at_every_precision():
    """Weighted a = b = 1, ff, k = 2, ratios 1: rho - 1 = 4.96e-9 (150-digit mpmath), proven unstable whatever
    precision the value is asked in; the digits printed agree with the 150-digit value."""
    point = ["--k", "2", "--li1", "0.3", "--lr1=-0.07611414651931382", *ONES]
    base = ["rho", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff", *point, "--json"]
    model = TestModel(Fraction("-0.07611414651931382"), Fraction(3, 10), 1, 1, 1)
    ref = spectral_radius_mp(model, make_method("weighted", a=1, b=1), "ff", 2, 150)
    assert 4.9e-9 < ref - 1 < 5e-9
    for extra in ([], ["--digits", "16"], ["--digits", "40"], ["--digits", "128"]):
        out = json_main(base + extra)
        assert out["verdict"] == "unstable" and out["certified"] is True
        with mpmath.workdps(150):
            assert abs(mpmath.mpf(out["rho_decimal"]) - ref) <= mpmath.mpf(10) ** -(out["digits"] - 1)


def json_main(argv):
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(argv) == 0
    return strict_loads(buf.getvalue())


def test_timeout_gives_undecided_with_the_reason():
    out = json_main(
        ["rho", *WEIGHTED, "--lr1", "-0.05", "--li1", "0.05", *ONES, "--digits", "2000", "--timeout", "0.2", "--json"]
    )
    assert out["verdict"] == "undecided" and out["rho"] is None and out["reason"].startswith("timeout")


def test_time_budget_interrupts_and_restores():
    with pytest.raises(PointTimeout):
        with time_budget(0.05):
            while True:
                pass
    with time_budget(1.0):  # a budget not used up leaves nothing behind
        pass
    import signal

    assert signal.getitimer(signal.ITIMER_REAL)[0] == 0


def test_a_grid_with_overflowing_and_capped_points_decides_every_other_point():
    """One call over five points: two overflow float64 (k2 not finite), one needs guard digits beyond the cap;
    each is undecided with its reason code, and the other two get the verdicts of their own proofs."""
    lr1 = np.array([-0.05, -0.05, -0.05, -1e6, -0.3])
    li1 = np.array([0.0, 0.05, 0.3, 0.05, 0.05])
    model = TestModel(lr1, li1, 1.0, np.array([1e200, 1, 1, 1, 1]), np.array([1, 1e300, 1, 1, 1]))
    method = make_method("weighted", a=1, b=1)
    for policy in ("auto", "certify", "mp"):
        t0 = time.perf_counter()
        res = spectral_radius(model, method, "ff", 2, policy=policy)
        assert time.perf_counter() - t0 < 60
        assert list(res.reason_code[:2]) == ["overflow", "overflow"] and res.reason_code[3] == "precision_cap"
        assert list(res.verdict) == ["undecided", "undecided", "unstable", "undecided", "stable"]
        for i in (2, 4):
            ref = spectral_radius_mp(TestModel(lr1[i], li1[i]), method, "ff", 2, 60)
            assert res.rho[i] == pytest.approx(float(ref), rel=1e-12)


# -- property-based: any accepted point ------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)
scales = st.sampled_from([0.0, 1e-300, 1e-12, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e12, 1e150, 1e300])


@st.composite
def points(draw):
    """A point over the whole accepted range: signs as the test model requires, magnitudes from 0 to 1e300."""
    lr1 = -draw(scales) * draw(st.floats(0, 2))
    li1 = draw(scales) * draw(st.floats(0, 2))
    am21 = draw(st.sampled_from([1e-300, 1e-6, 0.5, 1.0, 2.0, 10.0, 1e6, 1e300]))
    alr21, ali21 = draw(scales), draw(scales)
    method = draw(st.sampled_from(["projection", "weighted", "baumgarte"]))
    dec = draw(st.sampled_from(["ff", "fd"] + (["dd"] if method == "projection" else [])))
    k = draw(st.integers(0, MAX_K))
    params = {"weighted": ["--a", "1", "--b", "1"], "baumgarte": ["--index", "1", "--mu", "1"], "projection": []}
    argv = ["rho", "--method", method, *params[method], "--decomposition", dec, "--k", str(k)]
    values = {"lr1": lr1, "li1": li1, "am21": am21, "alr21": alr21, "ali21": ali21}
    return argv + [f"--{n}={v!r}" for n, v in values.items()]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(points())
@example(  # an undamped point at 1495 rad per step: 2 digits proven by default, 14 at 40 digits
    ["rho", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff", "--k", "1"]
    + ["--lr1=-0.0", "--li1=1494.8333829606447", "--am21=1.0", "--alr21=0.0", "--ali21=10.0"]
)
def test_any_accepted_point_answers_in_strict_json_and_its_verdict_does_not_depend_on_the_digits(argv):
    import contextlib
    import io

    answers = []
    for extra in ([], ["--digits", "40"]):  # the default (17 digits) and 40
        buf, errbuf = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(errbuf):
            try:
                code = main(argv + extra + ["--json", "--timeout", "20"])
            except SystemExit as exc:  # argparse: bad input
                code = exc.code
        assert code in (0, 2)
        if code == 2:
            assert "error: argument" in errbuf.getvalue()
            return
        answers.append(strict_loads(buf.getvalue()))
    a, b = answers
    if "timeout" not in (a["reason_code"], b["reason_code"]):  # a timeout is the machine's, not the answer's
        assert a["verdict"] == b["verdict"]
    if a["rho"] is not None and b["rho"] is not None:
        if a.get("rho_lower") and b.get("rho_lower"):  # two proven enclosures of the same rho must overlap
            from decimal import Decimal

            assert max(Decimal(a["rho_lower"]), Decimal(b["rho_lower"])) <= min(
                Decimal(a["rho_upper"]), Decimal(b["rho_upper"])
            )
            width = float(Decimal(a["rho_upper"]) - Decimal(a["rho_lower"]))
            width += float(Decimal(b["rho_upper"]) - Decimal(b["rho_lower"]))
        else:
            width = 0.0
        assert abs(a["rho_float"] - b["rho_float"]) <= width + 1e-6 * max(1.0, abs(b["rho_float"]))


def test_a_point_1e_400_from_the_undamped_axis_gets_one_verdict_at_every_digits():
    """lr1 = -1e-400 (typed; no double holds it): rho is within ~1e-400 of 1, so the 1024-bit cap cannot separate
    it from 1.  Asking for 400 or 2000 digits narrows enclosures, but must not turn the verdict into another one
    (it did: the digits raised the cap, and 2000 digits proved 'stable' where the default said 'marginal')."""
    argv = ["rho", "--method", "projection", "--decomposition", "ff", "--k", "1", "--lr1=-1e-400", "--li1", "0.3"]
    argv += ["--am21", "1", "--alr21", "1", "--ali21", "1", "--json"]
    verdicts = set()
    for extra in ([], ["--digits", "400"], ["--digits", "2000"]):
        verdicts.add(_json(argv + extra)["verdict"])
    assert verdicts == {"marginal"}


def test_a_damping_whose_square_overflows_is_undecided_with_its_reason_not_a_traceback():
    """lr1 = -1e154: k1 = lr1^2 = 1e308 is still a double, d^2/4 is not; the decay rate is formed without the
    square, and the guard bits it needs (~1e154 / ln 2) exceed the cap: undecided, reason precision_cap."""
    argv = ["rho", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff", "--k", "1"]
    answer = _json(argv + ["--lr1=-1e154", "--li1", "0", "--am21", "1", "--alr21", "1", "--ali21", "1", "--json"])
    assert answer["verdict"] == "undecided" and answer["reason_code"] == "precision_cap" and answer["rho"] is None


def test_time_budget_outside_the_main_thread_runs_unbudgeted_and_a_huge_timeout_is_refused():
    import threading

    seen = []
    thread = threading.Thread(target=lambda: seen.append(_budgeted_sleep(0.01, 0.2)))
    thread.start()
    thread.join()
    assert seen == ["finished"]  # no SIGALRM from a worker thread: the block ran to its end
    with pytest.raises(SystemExit) as exc:
        main(
            ["rho", "--method", "projection", "--decomposition", "ff", "--k", "0", "--lr1=-0.1", "--li1", "0.1"]
            + ["--am21", "1", "--alr21", "1", "--ali21", "1", "--timeout", "1e12"]
        )
    assert exc.value.code == 2


def _budgeted_sleep(budget, seconds):
    with time_budget(budget):
        time.sleep(seconds)
    return "finished"


def _json(argv):
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(argv) == 0
    return strict_loads(buf.getvalue())


# -- configuration fuzz: a wrong value is a schema error before any job ---------------------------------


def _paths(obj, prefix=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list) and obj:
        for i, v in enumerate(obj[:2]):
            yield from _paths(v, prefix + (i,))
    yield prefix


@functools.cache
def _stability_config():
    """config/stability.yaml's stability part, read once (each example changes a deep copy)."""
    import yaml
    from helpers import ROOT

    return yaml.safe_load((ROOT / "config/stability.yaml").read_text())["stability"]


WRONG = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**20), 10**20),
    st.floats(),  # NaN and infinities too
    st.text(max_size=8),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_a_wrong_stability_value_fails_validation_or_is_harmless(data):
    """Replace one value of the stability configuration by a random one of any type: either the schema (or
    the parse-time panel construction, naming the key) refuses it, or every panel it implies is valid."""
    import copy

    from helpers import validate_config
    from snakemake.exceptions import WorkflowError

    from icosim.errors import ParameterError
    from icosim.studies.stability.panels import figure_panels

    cfg = copy.deepcopy(_stability_config())
    paths = [p for p in _paths(cfg) if p]
    path = data.draw(st.sampled_from(paths))
    target = cfg
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = data.draw(WRONG)
    try:
        validate_config(cfg, "stability")
    except WorkflowError:
        return  # refused by the schema, naming the key
    try:
        figures = {str(f): c for f, c in cfg["figures"].items()}
        specs = [
            spec
            for fig, fc in figures.items()
            for spec in figure_panels(fig, fc, grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"])
        ]
    except ParameterError:
        return  # refused at parse time, naming the figure and key
    for spec in specs:  # accepted: then the job's own parameters are all valid
        spec.coupling_method()


@pytest.mark.parametrize("n", [4294967296.0, 1.152921504606847e18, 10002])
def test_a_huge_grid_is_refused_before_any_allocation(n):
    """Hypothesis found these: an integral float passes the schema's ``integer`` and numpy then tried to
    allocate 32 GiB (or raised 'array is too big'); now the schema and the panel construction refuse it."""
    import copy

    import yaml
    from helpers import ROOT, validate_config
    from snakemake.exceptions import WorkflowError

    from icosim.engine.bounds import MAX_GRID_N
    from icosim.errors import ParameterError
    from icosim.studies.stability.panels import grid_axis

    cfg = copy.deepcopy(yaml.safe_load((ROOT / "config/stability.yaml").read_text())["stability"])
    cfg["grid"]["n"] = n
    with pytest.raises(WorkflowError):
        validate_config(cfg, "stability")
    with pytest.raises(ParameterError, match=str(MAX_GRID_N)):
        grid_axis([-1.0, 0.0], n)


# -- datasets: checksums and stale temporaries ----------------------------------------------------------


def test_a_corrupt_dataset_is_refused_and_set_aside_and_stale_temporaries_removed(tmp_path):
    import xarray as xr

    from icosim.errors import CorruptDatasetError
    from icosim.io.netcdf import open_attributes, open_dataset, write_netcdf

    path = tmp_path / "results" / "fig9" / "r1_k0_full.nc"
    attrs = {"title": "t", "k": np.int64(2), "rho_max": 1.5, "n_points": np.int32(4), "shares": np.array([0.5, 0.25])}
    write_netcdf(xr.Dataset({"rho": ("x", np.arange(4.0))}, attrs=attrs), path)
    assert verify(path) is True and sidecar(path).read_text().split()[1] == path.name
    assert open_dataset(path)["rho"].values.tolist() == [0, 1, 2, 3]
    # the attributes alone (without the variables), with the types and values open_dataset gives
    whole, alone = open_dataset(path).attrs, open_attributes(path)
    assert list(alone) == list(whole) == list(attrs)
    for name, value in whole.items():
        assert type(alone[name]) is type(value) and np.array_equal(alone[name], value), name
    raw = bytearray(path.read_bytes())
    raw[-20] ^= 0xFF  # one damaged byte
    path.write_bytes(bytes(raw))
    with pytest.raises(CorruptDatasetError, match="SHA-256"):
        open_dataset(path)
    with pytest.raises(CorruptDatasetError, match="SHA-256"):
        open_attributes(path)
    stale = path.parent / ".r1_k1_full.nc.abc123.part"
    stale.write_bytes(b"half a file")
    assert quarantine_corrupt(tmp_path / "results") == [path.with_name(path.name + ".corrupt")]
    assert not path.exists() and not sidecar(path).exists()
    assert remove_stale_parts(tmp_path / "results") == [stale] and not stale.exists()
