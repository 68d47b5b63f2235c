"""``icosim rho --chain`` and ``icosim advise --chain``: a chain's answer equals the two-unit command's for two
single masses and ChainFamily's for three units; bad input exits 2 naming the argument before any work."""

import json

import numpy as np
import pytest
from helpers import ROOT

from icosim import make_method
from icosim.advise.core import TwoMassSystem
from icosim.cli import main
from icosim.engine.spectral.radius import spectral_radius_float64
from icosim.io.yamlio import load_yaml
from icosim.problems.linear.chain import Chain, ChainFamily
from icosim.studies.chains.config import scheme_name

TWO = {"m1": 1.0, "m2": 2.0, "c1": 1000.0, "c2": 500.0, "d1": 2.0, "d2": 1.0}
EXAMPLE = str(ROOT / "config" / "chains" / "example3.yaml")


def chain_file(tmp_path, segments, joints="ff"):
    path = tmp_path / "chain.yaml"
    path.write_text(json.dumps({"segments": segments, "joints": joints}))  # JSON is YAML
    return str(path)


def two_masses(tmp_path, decomposition):
    segs = [
        {"masses": [TWO[f"m{i}"]], "ground_stiffness": [TWO[f"c{i}"]], "ground_damping": [TWO[f"d{i}"]]} for i in (1, 2)
    ]
    return chain_file(tmp_path, segs, decomposition)


def answer(capsys, argv):
    assert main(argv + ["--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    "decomposition,scheme,pair_scheme",
    [("ff", "jacobi", "jacobi"), ("fd", "gauss-seidel-reverse", "gauss-seidel-21"), ("df", "1,2", "gauss-seidel-12")],
)
@pytest.mark.parametrize("method", [["projection"], ["baumgarte", "--index", "1", "--mu", "1"]])
def test_two_single_masses_equal_the_two_unit_command(capsys, tmp_path, decomposition, scheme, pair_scheme, method):
    """The chain of two single masses through ChainFamily, the two-unit command through the test model's parameters
    (Eq. 71) of the same system: two routes to one rho."""
    H = 0.01
    p = TwoMassSystem(**TWO).dimensionless(H)
    pair = ["rho", "--method", *method, "--k", "2", "--decomposition", decomposition, "--scheme", pair_scheme]
    pair += [t for n in ("lr1", "li1", "am21", "alr21", "ali21") for t in (f"--{n}", repr(p[n]))]
    chain = ["rho", "--chain", two_masses(tmp_path, decomposition), "--H", str(H), "--method", *method, "--k", "2"]
    a, b = answer(capsys, pair), answer(capsys, chain + ["--scheme", scheme])
    assert b["scheme"] == pair_scheme and b["certified"] and b["verdict"] == a["verdict"]
    assert b["rho"] == pytest.approx(a["rho"], rel=1e-12)


@pytest.mark.parametrize(
    "method,params,k,scheme",
    [
        ("projection", {}, 1, "jacobi"),
        ("weighted", {"index": 1, "a": 1, "b": 1}, 2, "jacobi"),
        ("baumgarte", {"index": 1, "mu": 1}, 1, "gauss-seidel-reverse"),
        ("projection", {}, 2, "2,1,3"),
    ],
)
def test_three_units_equal_chain_family_and_the_verdict_follows_rho(capsys, method, params, k, scheme):
    H = 0.01
    argv = ["rho", "--chain", EXAMPLE, "--H", str(H), "--method", method, "--k", str(k), "--scheme", scheme]
    argv += [t for name, v in params.items() for t in (f"--{name}", str(v))]
    got = answer(capsys, argv)
    with open(EXAMPLE) as f:
        chain = Chain.from_dict(load_yaml(f), H)
    name = "gauss-seidel-" + scheme.replace(",", "") if "," in scheme else scheme_name(scheme, 3)
    rho, err = map(float, spectral_radius_float64(ChainFamily(chain, k), make_method(method, **params), scheme=name))
    assert got["scheme"] == name and got["units"] == 3 and got["certified"]
    assert got["rho"] == pytest.approx(rho, rel=1e-12)
    assert abs(rho - 1) > err  # float64 decides it too: the proof must agree
    assert got["verdict"] == ("stable" if rho < 1 else "unstable") and got["stable"] is (rho < 1)


def test_the_example_has_both_verdicts_and_the_text_names_them(capsys):
    """The example chain at H = 0.01 s: stable with the projection at k = 1, unstable with the weighted multiplier
    at k = 2 (as ChainFamily's float64 rho says, checked above); the text line states the verdict."""
    base = ["rho", "--chain", EXAMPLE, "--H", "0.01"]
    assert main(base + ["--method", "projection", "--k", "1"]) == 0
    assert "stable, proven" in capsys.readouterr().out
    assert main(base + ["--method", "weighted", "--index", "1", "--a", "1", "--b", "1", "--k", "2"]) == 0
    assert "unstable, proven" in capsys.readouterr().out


def bad_files(tmp_path):
    seg = {"masses": [1.0], "ground_stiffness": [100.0]}
    return {
        "missing": (str(tmp_path / "none.yaml"), "cannot be read"),
        "key": (chain_file(tmp_path / "k", [{"mass": [1.0]}, seg]), "segments[0]"),
        "joint": (chain_file(tmp_path / "j", [seg, seg], "xy"), "joints[0]: must be one of ff, fd, df, dd"),
    }


@pytest.mark.parametrize("case", ["missing", "key", "joint"])
def test_a_bad_chain_file_exits_2_naming_the_key(capsys, tmp_path, monkeypatch, case):
    for d in ("k", "j"):
        (tmp_path / d).mkdir()
    path, text = bad_files(tmp_path)[case]
    _no_work(monkeypatch)
    with pytest.raises(SystemExit) as exc:
        main(["rho", "--chain", path, "--H", "0.01", "--method", "projection", "--k", "1"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "argument --chain" in err and text in err and "Traceback" not in err


def _no_work(monkeypatch):
    import icosim.cli.rho

    def no_work(*a, **k):
        raise AssertionError("computed before the input was checked")

    monkeypatch.setattr(icosim.cli.rho, "family_answer", no_work)


@pytest.mark.parametrize(
    "extra,argument,text",
    [
        (["--scheme", "bogus"], "--scheme", "gauss-seidel-forward"),  # the allowed values listed
        (["--scheme", "1,3"], "--scheme", "each of the units 1 ... 3"),  # an order missing a unit
        (["--scheme", "gauss-seidel-21"], "--scheme", "each of the units 1 ... 3"),
        (["--lr1", "-0.1", "--decomposition", "ff"], "--chain", "--decomposition, --lr1"),
        (
            ["--method", "weighted", "--index", "1", "--a", "1", "--b", "1", "--scheme", "1,3,2"],
            "--method/--scheme",
            "gauss-seidel-132",
        ),  # fmt: skip
        (["--H", "0"], "--H", "> 0"),
    ],
)
def test_refusals_exit_2_naming_the_argument(capsys, monkeypatch, extra, argument, text):
    _no_work(monkeypatch)
    with pytest.raises(SystemExit) as exc:
        main(["rho", "--chain", EXAMPLE, "--H", "0.01", "--method", "projection", "--k", "1", *extra])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and f"argument {argument}" in err and text in err and "Traceback" not in err


def test_without_a_chain_the_two_unit_arguments_stay_required_and_h_is_refused(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["rho", "--method", "projection", "--k", "1", "--lr1", "-0.1"])
    assert exc.value.code == 2 and "--decomposition, --li1" in capsys.readouterr().err
    pair = ["--lr1", "-0.1", "--li1", "1", "--am21", "1", "--alr21", "1", "--ali21", "1", "--decomposition", "ff"]
    for extra, argument in ((["--H", "0.01"], "--H"), (["--scheme", "gauss-seidel-forward"], "--scheme")):
        with pytest.raises(SystemExit) as exc:
            main(["rho", "--method", "projection", "--k", "1", *pair, *extra])
        assert exc.value.code == 2 and f"argument {argument}" in capsys.readouterr().err


def test_advise_ranks_the_chain_and_lists_the_refused_orders(capsys):
    argv = ["advise", "--chain", EXAMPLE, "--H", "0.01", "--k", "1", "--methods", "projection", "weighted"]
    data = answer(capsys, argv + ["--schemes", "jacobi", "gauss-seidel-reverse", "1,3,2"])
    rows = data["configurations"]
    refused = {r["configuration"]: r["reason"] for r in data["refused"]}
    # the weighted multiplier has no acceleration-level condition: the middle unit after both neighbours is refused
    assert len(refused) == 3 and all("gauss-seidel-132" in c and c.startswith("weighted") for c in refused)
    assert all("cannot serve method weighted" in why for why in refused.values())
    assert {r["scheme"] for r in rows} == {"jacobi", "gauss-seidel-321", "gauss-seidel-132"}
    ranked = [r for r in rows if r["rank"] is not None]
    assert [r["rank"] for r in ranked] == list(range(1, len(ranked) + 1))
    assert all(r["verdict"] == "stable" for r in ranked) and all(r["rank"] is None for r in rows[len(ranked) :])
    assert np.all(np.diff([r["rho"] for r in ranked]) >= 0)
    row = next(r for r in rows if r["configuration"] == "projection ff-ff k=1 gauss-seidel-321")
    one = answer(
        capsys,
        ["rho", "--chain", EXAMPLE, "--H", "0.01", "--method", "projection", "--k", "1", "--scheme", "3,2,1"],
    )
    assert row["rho"] == pytest.approx(one["rho"], rel=1e-12)
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "Chain of 3 units" in out and "projection ff-ff k=1 gauss-seidel-123" in out


def test_advise_over_a_range_gives_a_largest_stable_h(capsys):
    argv = ["advise", "--chain", EXAMPLE, "--H", "1e-3", "0.1", "--k", "1", "--methods", "projection"]
    data = answer(capsys, argv + ["--schemes", "jacobi", "--scan", "8", "--rtol", "1e-3"])
    (row,) = data["configurations"]
    with open(EXAMPLE) as f:
        chain = Chain.from_dict(load_yaml(f))
    H = row["H_max"]
    rho = spectral_radius_float64(ChainFamily(chain.with_H(np.array([H, row["unstable_above"]])), 1),
                                  make_method("projection"))[0]  # fmt: skip
    assert rho[0] < 1 < rho[1] and row["unstable_above"] / H <= 1 + 1e-3


@pytest.mark.parametrize(
    "extra,argument",
    [
        (["--m1", "1"], "--chain"),
        (["--decompositions", "ff"], "--chain"),
        (["--schemes", "1,2"], "--schemes"),
        (["--schemes", "gauss-seidel-12"], "--schemes"),
    ],
)
def test_advise_refusals_exit_2_naming_the_argument(capsys, monkeypatch, extra, argument):
    import icosim.advise.core

    def no_work(*a, **k):
        raise AssertionError("computed before the input was checked")

    monkeypatch.setattr(icosim.advise.core, "spectral_radius", no_work)
    with pytest.raises(SystemExit) as exc:
        main(["advise", "--chain", EXAMPLE, "--H", "0.01", *extra])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and f"argument {argument}" in err and "Traceback" not in err
