"""The ``icosim rho`` command: results equal the library's, bad input exits 2 naming the argument."""

import json
import subprocess
import sys

import pytest

from icosim import TestModel, baumgarte, spectral_radius_float64, weighted_multiplier
from icosim.cli import main
from icosim.engine.schemes import GS12, GS21, JACOBI, SCHEMES, GaussSeidel, get_scheme

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
    assert data["rho_float64"] == float(expected)  # float64's own value beside the proven one
    # the value is the midpoint of the proven enclosure narrowed to a double's 17 digits
    assert data["digits"] == 17 and data["stable"] is True and data["certified"] is True
    assert float(data["rho_lower"]) <= data["rho"] <= float(data["rho_upper"])
    assert data["method_parameters"] == {"beta": 2.0, "gamma": 1.0, "mu": 1.0, "index": 1}


def test_digits_option_prints_that_many_proven_digits(capsys):
    code, out = run(
        capsys, BASE + ["--method", "projection", "--decomposition", "dd", "--k", "1", "--digits", "40", "--json"]
    )
    data = json.loads(out)
    assert code == 0 and data["digits"] == 40
    ref, _ = spectral_radius_float64(TestModel(-0.5, 0.7, 2, 2, 2), __import__("icosim").projection(), "dd", 1)
    assert data["rho_float"] == pytest.approx(float(ref), rel=1e-12)
    assert isinstance(data["rho"], str) and len(data["rho"].replace("0.", "", 1).lstrip("0")) == 40


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


@pytest.mark.parametrize(
    "name,scheme,dec",
    [
        ("gauss-seidel-12", GS12, "fd"),
        ("gauss-seidel-21", GS21, "fd"),
        ("gauss-seidel-21-as-integrated", GaussSeidel(first=2, leading_outputs="as-integrated"), "ff"),
    ],
)
def test_gauss_seidel_scheme_matches_library(capsys, name, scheme, dec):
    argv = BASE + ["--method", "weighted", "--a", "1", "--b", "1", "--decomposition", dec, "--k", "1"]
    argv += ["--scheme", name, "--json"]
    code, out = run(capsys, argv)
    data = json.loads(out)
    expected, _ = spectral_radius_float64(
        TestModel(-0.5, 0.7, 2, 2, 2), weighted_multiplier(1, 1), dec, 1, scheme=scheme
    )
    # the scheme is spelled by its name only: the name says which subsystem advances first
    assert code == 0 and data["scheme"] == scheme.name == name and get_scheme(data["scheme"]) == scheme
    assert "first" not in data
    assert data["verdict"] in ("stable", "unstable") and data["certified"]
    assert data["rho"] == pytest.approx(float(expected), rel=1e-13)
    code, out = run(capsys, argv[:-1])
    assert scheme.label in out


def test_default_scheme_is_jacobi(capsys):
    code, out = run(capsys, BASE + ["--method", "projection", "--decomposition", "ff", "--k", "0", "--json"])
    data = json.loads(out)
    assert data["scheme"] == "jacobi" and get_scheme(data["scheme"]) is JACOBI and "first" not in data


@pytest.mark.parametrize(
    "extra,argument",
    [
        # the generic name of the old spelling (--scheme gauss-seidel --first 2) is not a scheme any more
        (["--scheme", "gauss-seidel"], "argument --scheme: invalid choice: 'gauss-seidel'"),
        # nor is --first an argument: the subsystem that advances first is part of the scheme's name
        (["--scheme", "gauss-seidel-12", "--first", "1"], "unrecognized arguments: --first 1"),
        (["--scheme", "gauss-seidel-31"], "argument --scheme: invalid choice: 'gauss-seidel-31'"),
        (["--scheme", "seidel"], "argument --scheme"),
    ],
)
def test_bad_scheme_arguments_exit_2_naming_them(capsys, extra, argument):
    with pytest.raises(SystemExit) as exc:
        main(BASE + ["--method", "projection", "--decomposition", "ff", "--k", "0"] + extra)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert argument in err and "Traceback" not in err
    if "--scheme" in argument:  # the allowed values are listed: every registered scheme
        assert all(f"'{name}'" in err for name in SCHEMES)


# -- N-digit results and numbers as users type them (every digit printed is proven) ------------------------
def test_digits_take_the_decimals_as_typed_and_print_n_digits(capsys):
    """``--lr1 -0.3 --digits 40`` computes at lr1 = -3/10 exactly (not the double -0.29999999999999998890) and prints
    40 significant digits: it equals the library at the exact decimal and differs from the double input's value."""
    from fractions import Fraction

    import mpmath

    from icosim import weighted_multiplier
    from icosim.problems.linear.spectral import spectral_radius_mp

    argv = ["rho", "--lr1", "-0.3", "--li1", "0.05", "--am21", "1.1", "--alr21", "0.7", "--ali21", "1.3"]
    argv += ["--method", "weighted", "--a", "0.1", "--b", "0.7", "--decomposition", "ff", "--k", "2"]
    code, out = run(capsys, argv + ["--digits", "40", "--json"])
    data = json.loads(out)
    m = weighted_multiplier(Fraction("0.1"), Fraction("0.7"))
    exact = spectral_radius_mp(TestModel(*(Fraction(v) for v in ("-0.3", "0.05", "1.1", "0.7", "1.3"))), m, "ff", 2, 60)
    doubles = spectral_radius_mp(TestModel(-0.3, 0.05, 1.1, 0.7, 1.3), weighted_multiplier(0.1, 0.7), "ff", 2, 60)
    with mpmath.workdps(60):
        got = mpmath.mpf(data["rho"])
        assert abs(got - exact) <= mpmath.mpf(10) ** -38 * exact  # 40 digits, the last one rounded
        assert abs(doubles - exact) > mpmath.mpf(10) ** -20 * exact  # the typed decimals matter at 40 digits
    code, text = run(capsys, argv + ["--digits", "40"])
    assert text.startswith(f"rho = {data['rho']}  (")


@pytest.mark.parametrize("value", ["-1e-3", "-2.5E-2", "-.5", "-3"])
def test_negative_numbers_as_users_type_them(capsys, value):
    """``--lr1 -1e-3`` (exponent notation after a space) is the number -1e-3, not an unknown option."""
    argv = ["rho", "--lr1", value, "--li1", "0.7", "--am21", "2", "--alr21", "2", "--ali21", "2"]
    code, out = run(capsys, argv + ["--method", "projection", "--decomposition", "ff", "--k", "1", "--json"])
    assert code == 0 and json.loads(out)["model"]["lr1"] == float(value)


def test_rho_at_128_and_160_digits_agree_to_120_digits():
    """The multiprecision path is exact end to end: on points of every scheme kind the 128- and 160-digit results
    agree to >= 120 digits (inputs exact, guard digits for the exponentials, exact method parameters)."""
    from fractions import Fraction

    import mpmath

    from icosim import make_method
    from icosim.problems.linear.spectral import spectral_radius_mp

    cases = [
        ("baumgarte", {"index": 1, "mu": "1"}, "ff", 2),
        ("baumgarte", {"index": 2, "mu": "0.25"}, "ff", 0),
        ("baumgarte", {"index": 1, "mu": "1"}, "fd", 1),
        ("weighted", {"a": "1", "b": "1"}, "ff", 2),
        ("weighted", {"a": "0.5", "b": "0.25"}, "fd", 0),
        ("weighted", {"index": 2, "a": "0.5"}, "ff", 1),
        ("baumgarte", {"index": 3}, "ff", 0),
        ("projection", {}, "ff", 1),
        ("projection", {}, "fd", 2),
        ("projection", {}, "dd", 0),
    ]
    points = ["-0.3 0.4 1 1 1", "-1.7 0.2 2 2 2", "-0.05 1.9 10 1 1", "-0.6 0.6 1 10 1", "-1 1.3 0.5 0.3 4"]
    for i, (name, params, dec, k) in enumerate(cases):
        method = make_method(name, **{key: Fraction(v) if isinstance(v, str) else v for key, v in params.items()})
        point = TestModel(*(Fraction(v) for v in points[i % len(points)].split()))
        r128 = spectral_radius_mp(point, method, dec, k, 128)
        r160 = spectral_radius_mp(point, method, dec, k, 160)
        with mpmath.workdps(170):
            assert abs(mpmath.mpf(r128) - mpmath.mpf(r160)) <= mpmath.mpf(10) ** -120 * abs(mpmath.mpf(r160)), (
                name,
                dec,
                k,
            )


def test_rho_and_the_parsers_import_no_table_or_plot_library():
    """``icosim rho`` builds every command's parser (advise's included) but answers without pandas,
    xarray or matplotlib: their imports would be most of a one-point answer's time."""
    code = (
        "import sys\nfrom icosim.cli import main\n"
        f"main({BASE + ['--method', 'projection', '--decomposition', 'dd', '--k', '1', '--json']!r})\n"
        "print(sorted({'pandas', 'xarray', 'matplotlib'} & set(sys.modules)), file=sys.stderr)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(proc.stdout)["verdict"] == "stable"
    assert proc.stderr.strip().splitlines()[-1] == "[]"
