"""``icosim advise``: every configuration for a physical two-mass system.

Expected values come from an independent route: the Eq. (71) point worked out by hand from
m, c, d and H (not through :class:`icosim.problems.linear.model.PhysicalModel`), evaluated with
:func:`icosim.problems.linear.spectral.spectral_radius_float64` on a :class:`~icosim.problems.linear.model.TestModel`.
"""

import io
import json
import math

import numpy as np
import pytest

from icosim import TestModel, make_method, spectral_radius_float64
from icosim.advise import Progress, TwoMassSystem, advice_records, advise, configurations
from icosim.cli import main
from icosim.problems.linear.model import Coefficients

SYSTEM = dict(m1=1.0, m2=2.0, c1=1e3, c2=2e3, d1=2.0, d2=4.0)
ARGS = ["--m1", "1", "--m2", "2", "--c1", "1e3", "--c2", "2e3", "--d1", "2", "--d2", "4"]


def by_hand(H, m1, m2, c1, c2, d1, d2):
    """Eq. (71) of the two-mass system, from the definitions lr = -d H/(2m), li = H sqrt(c/m - (d/2m)^2)."""
    lr1, lr2 = -d1 * H / (2 * m1), -d2 * H / (2 * m2)
    li1, li2 = H * math.sqrt(c1 / m1 - (d1 / (2 * m1)) ** 2), H * math.sqrt(c2 / m2 - (d2 / (2 * m2)) ** 2)
    return TestModel(lr1, li1, m2 / m1, lr2 / lr1, li2 / li1)


def rho_by_hand(H, scheme_method, dec, k, system=SYSTEM, scheme="jacobi"):
    rho, _ = spectral_radius_float64(by_hand(H, **system), scheme_method, dec, k, scheme=scheme)
    return float(rho)


def engine(row, H):
    """The method of a result row, with the engine's dimensionless parameters built by hand."""
    p = dict(row["method_parameters"])
    if "mu_bar" in p:
        p["mu"] = p.pop("mu_bar")
    elif "mu" in p:
        p["mu"] = p["mu"] / H
    if row["method"] != "projection":
        p["index"] = row["index"]
    return make_method(row["method"], **p)


def test_rho_at_one_H_equals_the_hand_computed_point():
    H = 1e-2
    df = advise(TwoMassSystem(**SYSTEM), H)
    # (27 Baumgarte + 27 weighted multiplier: 3 indices x (ff, fd, df) x 3 k; 12 projection: (ff, fd, df, dd) x 3 k)
    # x 3 schemes (the variants only when asked for)
    assert len(df) == 3 * 66
    assert df["scheme"].value_counts().to_dict() == {"jacobi": 66, "gauss-seidel-12": 66, "gauss-seidel-21": 66}
    assert set(df["decomposition"]) == {"ff", "fd", "df", "dd"}  # every registered decomposition, df included
    for _, row in df.iterrows():
        expected = rho_by_hand(H, engine(row, H), row["decomposition"], row["k"], scheme=row["scheme"])
        assert row["rho"] == pytest.approx(expected, rel=1e-12), row["configuration"]
        assert (row["verdict"] == "stable") == (expected <= 1)
    stable = df[df["verdict"] == "stable"]
    assert list(stable["rank"]) == list(range(1, len(stable) + 1))  # ranked first, by rho
    assert np.all(np.diff(stable["rho"].to_numpy()) >= 0) and df["rank"].isna().sum() == len(df) - len(stable)
    p = df.attrs["dimensionless"][0]
    point = by_hand(H, **SYSTEM)
    assert p["lr1"] == pytest.approx(point.lr1) and p["li1"] == pytest.approx(point.li1)
    assert (p["am21"], p["alr21"], p["ali21"]) == pytest.approx((2, 1, 1))


def test_baumgarte_mu_in_seconds_is_scaled_by_H():
    H, mu = 1e-2, 5e-3
    df = advise(
        TwoMassSystem(**SYSTEM),
        H,
        configuration_list=configurations(methods=["baumgarte"], k=[1], params={"mu": mu}, schemes=["jacobi"]),
    )
    row = df[(df["index"] == 1) & (df["decomposition"] == "ff")].iloc[0]
    assert row["parameters"] == "mu = 0.005 s"
    expected = rho_by_hand(H, make_method("baumgarte", index=1, mu=mu / H), "ff", 1)  # mu_bar = mu/H = 0.5
    assert row["rho"] == pytest.approx(expected, rel=1e-12)


def test_largest_stable_H_is_bracketed():
    """rho <= 1 at H_max, rho > 1 just above it (independently evaluated), bracket within rtol."""
    system = TwoMassSystem(**SYSTEM)
    rtol = 1e-6
    for method, dec, k in (("projection", "ff", 2), ("baumgarte", "fd", 0)):
        sl = [
            s for s in configurations(methods=[method], decompositions=[dec], k=[k], schemes=["jacobi"]) if s.index == 1
        ]
        row = advise(system, (1e-4, 1e-1), configuration_list=sl, rtol=rtol).iloc[0]
        assert row["verdict"] == "stable up to H_max" and row["stable_intervals"][0][0] == 1e-4
        H_max, above = row["H_max"], row["unstable_above"]
        assert 0 < above / H_max - 1 <= rtol
        m = engine(row, H_max)
        assert rho_by_hand(H_max, m, dec, k) <= 1 < rho_by_hand(above, m, dec, k)
        assert row["rho_at_H_max"] == pytest.approx(rho_by_hand(H_max, m, dec, k), rel=1e-12)
        assert row["rank"] == 1


def test_non_monotone_stability_is_reported_as_intervals():
    """Weighted multiplier ff, k = 2: unstable for small H (near the origin), stable above."""
    sl = configurations(methods=["weighted"], decompositions=["ff"], k=[2], schemes=["jacobi"])[:1]
    row = advise(TwoMassSystem(**SYSTEM), (1e-4, 1e-1), configuration_list=sl).iloc[0]
    [[lo, hi]] = row["stable_intervals"]
    assert row["verdict"] == "stable on intervals" and 1e-4 < lo < hi == 1e-1
    m = engine(row, lo)
    assert rho_by_hand(lo, m, "ff", 2) <= 1 < rho_by_hand(lo * (1 - 1e-5), m, "ff", 2)
    assert rho_by_hand(1e-4, m, "ff", 2) > 1
    assert "not monotone in H" in row["note"]
    assert row["unstable_above"] is None or np.isnan(row["unstable_above"])  # stable up to the range's end


def test_overdamped_subsystem_has_no_eq71_form_but_a_verdict():
    system = TwoMassSystem(m1=1, m2=1, c1=1, c2=100, d1=10, d2=1)  # d1^2 = 100 > 4 m1 c1 = 4
    H = 0.05
    df = advise(
        system,
        H,
        configuration_list=configurations(methods=["projection"], decompositions=["ff"], k=[0, 1], schemes=["jacobi"]),
    )
    p = df.attrs["dimensionless"][0]
    assert p["lr1"] is None and "subsystem 1 is overdamped" in p["eq71"]
    assert "lr1" not in df.columns
    coeff = Coefficients(k1=1 * H**2 / 1, delta1=10 * H / 1, k2=100 * H**2 / 1, delta2=1 * H / 1, am21=1.0)
    for _, row in df.iterrows():
        rho, _ = spectral_radius_float64(coeff, make_method("projection"), "ff", row["k"])
        assert row["rho"] == pytest.approx(float(rho), rel=1e-12)


def test_json_is_strict_and_explains_nulls(capsys):
    code = main(
        [
            "advise",
            *ARGS,
            "--H",
            "1e-3",
            "0.1",
            "--methods",
            "projection",
            "--k",
            "2",
            "--schemes",
            "jacobi",
            "--json",
        ]
    )
    assert code == 0
    out = capsys.readouterr().out

    def refuse(name):
        raise AssertionError(f"non-strict JSON constant {name}")

    data = json.loads(out, parse_constant=refuse)
    assert data["mode"] == "range" and len(data["configurations"]) == 4  # ff, fd, df, dd
    assert all(s["rank"] is not None for s in data["configurations"])  # projection k = 2 is stable for small H
    df = advise(
        TwoMassSystem(**SYSTEM),
        (1e-3, 0.1),
        configuration_list=configurations(methods=["projection"], k=[2], schemes=["jacobi"]),
    )
    assert [s["H_max"] for s in data["configurations"]] == pytest.approx(df["H_max"].tolist())
    # a scheme unstable everywhere: nulls with reasons
    rec = advice_records(
        advise(
            TwoMassSystem(**SYSTEM),
            (1e-3, 1e-2),
            configuration_list=[
                c
                for c in configurations(methods=["weighted"], k=[2], schemes=["jacobi"])
                if (c.index, c.decomposition) == (2, "ff")
            ],
        )
    )
    [s] = rec["configurations"]
    assert s["H_max"] is None and s["null_reasons"]["H_max"] == "no stable H in the range"
    assert s["rank"] is None and s["null_reasons"]["rank"] == "not stable"
    json.dumps(rec, allow_nan=False)


def test_text_output_ranks_the_stable_configurations(capsys):
    assert main(["advise", *ARGS, "--H", "0.01", "--methods", "projection", "--schemes", "jacobi"]) == 0
    out = capsys.readouterr().out
    assert "Eq. (71) at H = 0.01 s: lr1 = -0.01, li1 = 0.3161, am21 = 2, alr21 = 1, ali21 = 1" in out
    n_stable = sum(
        rho_by_hand(0.01, make_method("projection"), d, k) <= 1 for d in ("ff", "fd", "df", "dd") for k in (0, 1, 2)
    )
    assert f"12 configurations at H = 0.01 s, {n_stable} stable" in out  # (ff, fd, df, dd) x 3 k
    lines = [line for line in out.splitlines() if line.strip().startswith("1 ")]
    assert lines and "projection dd k=0" in lines[0]  # smallest rho at this point (Figs. 15: dd damps most)


@pytest.mark.parametrize(
    "extra,argument",
    [
        (["--m1", "0"], "--m1"),
        (["--c2", "-1"], "--c2"),
        (["--d1", "nan"], "--d1"),
        (["--H", "0"], "--H"),
        (["--H", "-1e-3"], "--H"),
        (["--H", "0.1", "0.01"], "--H"),
        (["--H", "0.1", "0.2", "0.3"], "--H"),
        (["--k", "-1"], "--k"),
        (["--methods", "nope"], "--methods"),
        (["--decompositions", "xy"], "--decompositions"),
        (["--schemes", "gauss-seidel"], "--schemes"),  # the old generic name: a scheme is named with its order
        (["--mu", "-1e-3"], "--mu"),
        (["--methods", "weighted", "--b", "0"], "--b"),
        (["--methods", "projection", "--a", "1"], "--a"),
        (["--policy", "mp"], "--policy"),
        (["--scan", "1"], "--scan"),
        (["--rtol", "2"], "--rtol"),
    ],
)
def test_bad_input_exits_2_before_any_work(capsys, monkeypatch, extra, argument):
    import icosim.advise.core

    def no_work(*a, **k):
        raise AssertionError("computed before the input was checked")

    monkeypatch.setattr(icosim.advise.core, "spectral_radius", no_work)
    argv = dict(zip(ARGS[::2], ARGS[1::2]))
    argv["--H"] = "1e-2"
    flat = [t for kv in argv.items() for t in kv]
    # later options replace earlier ones; --H with several values is given last
    base = [t for kv in argv.items() if kv[0] not in extra for t in kv]
    with pytest.raises(SystemExit) as exc:
        main(["advise", *(base if "--H" in extra else flat), *extra])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {argument}" in err and "Traceback" not in err
    assert len(err.strip().splitlines()[-1]) < 300


def test_progress_bar_only_on_a_terminal_after_the_delay():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    quiet, tty = io.StringIO(), Tty()
    for stream, delay in ((quiet, 0.0), (tty, 0.0)):
        bar = Progress(4, stream=stream, delay=delay)
        bar(2)
        bar.close()
    assert quiet.getvalue() == "" and "2/4 configurations" in tty.getvalue()
    late = Tty()
    bar = Progress(4, stream=late, delay=60.0)
    bar(4)
    assert late.getvalue() == ""  # a scan shorter than the delay shows nothing


def test_range_ranking_puts_configurations_stable_from_the_lower_end_first():
    sl = configurations(methods=["weighted"], decompositions=["ff"], k=[2], schemes=["jacobi"])[:1] + configurations(
        methods=["projection"], decompositions=["ff"], k=[2], schemes=["jacobi"]
    )
    df = advise(TwoMassSystem(**SYSTEM), (1e-4, 1e-1), configuration_list=sl)
    # weighted ff k = 2 reaches the larger H (0.1) but is unstable at small H: ranked after projection
    assert list(df["method"]) == ["projection", "weighted"] and list(df["rank"]) == [1, 2]
    assert df["H_max"].iloc[1] > df["H_max"].iloc[0]
    assert df["H_max_from_lo"].iloc[0] == df["H_max"].iloc[0] and np.isnan(df["H_max_from_lo"].iloc[1])


def test_schemes_option_selects_the_coupling_schemes(capsys):
    """``--schemes gauss-seidel-21``: only that scheme, its rho the library's with that scheme."""
    code = main(["advise", *ARGS, "--H", "1e-2", "--methods", "projection", "--k", "1", "--schemes", "gauss-seidel-21"])
    assert code == 0
    code = main(
        [
            "advise",
            *ARGS,
            "--H",
            "1e-2",
            "--methods",
            "projection",
            "--k",
            "1",
            "--schemes",
            "gauss-seidel-21",
            "--json",
        ]
    )
    data = json.loads(capsys.readouterr().out.splitlines()[-1])
    rows = data["configurations"]
    assert {s["scheme"] for s in rows} == {"gauss-seidel-21"} and len(rows) == 4  # ff, fd, df, dd
    for s in rows:
        expected = rho_by_hand(1e-2, make_method("projection"), s["decomposition"], 1, scheme="gauss-seidel-21")
        assert s["rho"] == pytest.approx(expected, rel=1e-12)
