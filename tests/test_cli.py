"""The ``icosim rho`` command: results equal the library's, bad input exits 2 naming the argument."""

import json
import subprocess
import sys

import pytest

from icosim import TestModel, baumgarte, spectral_radius_float64, weighted_multiplier
from icosim.cli import main
from icosim.schemes import GS12, GS21

BASE = ["rho", "--lr1", "-0.5", "--li1", "0.7", "--am21", "2", "--alr21", "2", "--ali21", "2"]


def run(capsys, argv):
    code = main(argv)
    return code, capsys.readouterr().out


def test_json_output_matches_library(capsys):
    code, out = run(
        capsys,
        BASE + ["--method", "baumgarte", "--index", "1", "--mu", "1", "--decomposition", "ff", "--k", "2", "--json"],
    )
    assert code == 0
    data = json.loads(out)
    expected, _ = spectral_radius_float64(TestModel(-0.5, 0.7, 2, 2, 2), baumgarte(mu=1, index=1), "ff", 2)
    assert data["rho"] == pytest.approx(float(expected), rel=1e-13)
    assert data["digits"] == 15 and data["stable"] is True
    assert data["method_parameters"] == {"beta": 2.0, "gamma": 1.0, "mu": 1.0, "index": 1}


def test_digits_option_uses_multiprecision(capsys):
    code, out = run(
        capsys, BASE + ["--method", "projection", "--decomposition", "dd", "--k", "1", "--digits", "40", "--json"]
    )
    data = json.loads(out)
    assert code == 0 and data["digits"] == 40
    ref, _ = spectral_radius_float64(TestModel(-0.5, 0.7, 2, 2, 2), __import__("icosim").projection(), "dd", 1)
    assert data["rho"] == pytest.approx(float(ref), rel=1e-12)


@pytest.mark.parametrize(
    "extra,argument",
    [
        (["--method", "nope", "--decomposition", "ff", "--k", "0"], "--method"),
        (["--method", "projection", "--decomposition", "ff", "--k", "-1"], "--k"),
        (["--method", "projection", "--decomposition", "xx", "--k", "0"], "--decomposition"),
        (["--method", "baumgarte", "--decomposition", "ff", "--k", "0"], "Baumgarte needs"),
        (["--method", "baumgarte", "--index", "1", "--decomposition", "ff", "--k", "0"], "--mu"),
        (["--method", "weighted", "--a", "1", "--b", "nan", "--decomposition", "ff", "--k", "0"], "--b"),
        (["--method", "projection", "--a", "1", "--decomposition", "ff", "--k", "0"], "--a"),
        (["--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "dd", "--k", "0"], "position level"),
        (["--method", "projection", "--decomposition", "ff", "--k", "0", "--digits", "8"], "--digits"),
    ],
)
def test_bad_input_exits_2_naming_the_argument(capsys, extra, argument):
    with pytest.raises(SystemExit) as exc:
        main(BASE + extra)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert argument in err and "Traceback" not in err


@pytest.mark.parametrize("flag,value", [("--am21", "0"), ("--am21", "-1"), ("--lr1", "nan"), ("--lr1", "0.5")])
def test_bad_model_parameter_names_it(capsys, flag, value):
    argv = [a for a in BASE]
    argv[argv.index(flag) + 1] = value
    with pytest.raises(SystemExit) as exc:
        main(argv + ["--method", "projection", "--decomposition", "ff", "--k", "0"])
    assert exc.value.code == 2
    assert flag in capsys.readouterr().err


def test_missing_parameter_and_real_process_exit_status():
    argv = [
        sys.executable,
        "-m",
        "icosim.cli",
        "rho",
        "--method",
        "projection",
        "--decomposition",
        "ff",
        "--k",
        "0",
        "--lr1",
        "-1",
        "--li1",
        "1",
        "--am21",
        "1",
        "--alr21",
        "1",
    ]
    proc = subprocess.run(argv, capture_output=True, text=True)
    assert proc.returncode == 2
    assert "--ali21" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("first,scheme", [(None, GS12), ("1", GS12), ("2", GS21)])
def test_gauss_seidel_scheme_matches_library(capsys, first, scheme):
    argv = BASE + ["--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "fd", "--k", "1"]
    argv += ["--scheme", "gauss-seidel"] + (["--first", first] if first else []) + ["--json"]
    code, out = run(capsys, argv)
    data = json.loads(out)
    expected, _ = spectral_radius_float64(
        TestModel(-0.5, 0.7, 2, 2, 2), weighted_multiplier(1, 1), "fd", 1, scheme=scheme
    )
    assert code == 0 and data["scheme"] == scheme.name
    assert data["rho"] == pytest.approx(float(expected), rel=1e-13)
    code, out = run(capsys, argv[:-1])
    assert scheme.label in out


def test_default_scheme_is_jacobi(capsys):
    code, out = run(capsys, BASE + ["--method", "projection", "--decomposition", "ff", "--k", "0", "--json"])
    assert json.loads(out)["scheme"] == "jacobi"


@pytest.mark.parametrize(
    "extra,argument",
    [
        (["--first", "2"], "argument --first: only used with --scheme gauss-seidel"),
        (["--scheme", "jacobi", "--first", "1"], "argument --first"),
        (["--scheme", "gauss-seidel", "--first", "3"], "argument --first"),
        (["--scheme", "seidel"], "argument --scheme"),
    ],
)
def test_bad_scheme_arguments_exit_2_naming_them(capsys, extra, argument):
    with pytest.raises(SystemExit) as exc:
        main(BASE + ["--method", "projection", "--decomposition", "ff", "--k", "0"] + extra)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert argument in err and "Traceback" not in err
