"""The claim machinery (icosim.verdicts) and the stability claims file.

Synthetic panels with a known stable region test each check kind's pass /
fail / undecided logic; one real coarse panel computed with the engine checks
a claim end to end.
"""

import numpy as np
import pytest
import xarray as xr
import yaml
from helpers import ROOT

from icosim.claims.registry import CHECKS, DEFAULTS, evaluate, evaluate_claim, load_claims, parse_claims
from icosim.errors import ParameterError
from icosim.report.claims import claims_table
from icosim.studies.stability.checks import grid_resolution, stable_share
from icosim.studies.stability.datasets import stability_panel
from icosim.studies.stability.panels import PanelSpec, figure_panels, figure_schemes
from icosim.verdicts import enforce_references, read_verdicts, reference_mismatches, select, write_verdicts

CLAIMS_FILE = ROOT / "config" / "claims" / "stability.yaml"
CONFIG_FILE = ROOT / "config" / "stability.yaml"


def panel(stable_cols: int, n: int = 11, lr=(-2.0, 0.0), li=(0.0, 2.0), **attrs):
    """A synthetic panel on an n x n grid whose first `stable_cols` lr1 columns are stable."""
    lr1 = np.linspace(*lr, n)
    li1 = np.linspace(*li, n)
    stable = np.zeros((n, n), dtype=bool)
    stable[:stable_cols, :] = True
    rho = np.where(stable, 0.5, 1.5)
    # as an engine panel: the figure and the coupling scheme apart (a selector naming no scheme reads Jacobi's)
    base = {
        "figure": "9",
        "scheme": "jacobi",
        "row": 1,
        "k": 0,
        "view": "full",
        "am21": 1.0,
        "alr21": 1.0,
        "ali21": 1.0,
    }
    base.update(attrs)
    return xr.Dataset(
        {"rho": (("lr1", "li1"), rho), "stable": (("lr1", "li1"), stable)},
        coords={"lr1": lr1, "li1": li1},
        attrs=base,
    )


def claim(check, **extra):
    item = {"id": "c", "source": "test", "statement": "test", "figures": ["9"], "check": check}
    item.update(extra)
    return parse_claims([item])[0]


# -- selection and shares ----------------------------------------------------------------


def test_select_matches_numbers_numerically_and_lists():
    ds = [panel(5, row=r, k=k, am21=10.0 if r == 2 else 1.0) for r in (1, 2) for k in (0, 1)]
    assert len(select(ds, {"figure": 9})) == 4  # "9" == 9
    assert len(select(ds, {"am21": 10})) == 2  # 10 == 10.0
    assert len(select(ds, {"k": [0, 1], "row": 2})) == 2
    assert select(ds, {"method": "weighted"}) == []  # attribute absent: no match


def test_stable_share_counts_points_and_region():
    ds = panel(4, n=11)  # columns lr1 = -2.0 ... -1.4 stable
    share = stable_share(ds)
    assert (share.stable, share.open, share.n) == (44, 0, 121) and share.low == share.high == pytest.approx(44 / 121)
    share = stable_share(ds, {"lr1": [-2.0, -1.5]})  # 3 columns, all stable
    assert (share.stable, share.n) == (33, 33)
    assert stable_share(ds, {"exclude_undamped": True}).n == 110  # the column lr1 = 0 is left out
    with pytest.raises(ParameterError, match="region"):
        stable_share(ds, {"lr2": [0, 1]})
    with pytest.raises(ParameterError, match="no grid point"):
        stable_share(ds, {"lr1": [0.5, 1.0]})


def test_grid_resolution_is_one_spacing_of_the_coarsest_grid():
    assert grid_resolution([panel(1, n=11), panel(1, n=21)]) == pytest.approx(0.1)


# -- check kinds -----------------------------------------------------------------------------


def test_stable_fraction_pass_fail_and_missing_data():
    ds = [panel(11, row=1), panel(0, row=2)]
    only_stable = {"kind": "stable_fraction", "select": {"figure": "9", "row": 1}, "op": "==", "value": 1}
    assert evaluate_claim(claim(only_stable), ds).verdict == "pass"
    none_stable = {**only_stable, "select": {"row": 2}, "value": 0}
    assert evaluate_claim(claim(none_stable), ds).verdict == "pass"
    assert evaluate_claim(claim({**only_stable, "select": {"row": [1, 2]}}), ds).verdict == "fail"
    missing = evaluate_claim(claim({**only_stable, "select": {"figure": "99"}}), ds)
    assert missing.verdict == "undecided" and "no dataset" in missing.measured


def test_unstable_near_origin_ignores_the_undamped_axis_but_reports_it():
    ds = panel(10, n=11)  # only the column lr1 = 0 is unstable
    near_origin = {
        "kind": "stable_fraction",
        "select": {"figure": "9"},
        "region": {"lr1": [-0.5, 0.0], "li1": [0.0, 0.5], "exclude_undamped": True},
        "op": "<",
        "value": 1,
    }
    v = evaluate_claim(claim(near_origin), [ds])
    assert v.verdict == "fail"  # every damped point is stable
    assert "undamped axis" in v.measured
    ds9 = panel(9, n=11)  # the column lr1 = -0.2 is unstable too
    v = evaluate_claim(claim(near_origin), [ds9])
    assert v.verdict == "pass"
    (entry,) = v.numbers.values()
    assert entry["nearest_unstable_to_origin"] == pytest.approx(0.2)


@pytest.mark.parametrize(
    "cols_a, cols_b, relation, expected",
    [
        (8, 5, "greater", "pass"),
        (5, 8, "greater", "fail"),
        (6, 5, "greater", "undecided"),  # one column = one grid spacing: not resolved
        (5, 8, "less", "pass"),
        (6, 6, "similar", "pass"),
        (9, 3, "similar", "fail"),
        # `by`: at least 30 points (3 of the 11 columns = 27.3 %, 4 = 36.4 %; one column is the resolution)
        (9, 5, "greater by 0.3", "pass"),
        (7, 5, "greater by 0.3", "fail"),  # 18.2 points: short of 30 by more than one column
        (8, 5, "greater by 0.3", "undecided"),  # 27.3 points: within one column of 30
    ],
)
def test_compare_relations(cols_a, cols_b, relation, expected):
    ds = [panel(cols_a, figure="12"), panel(cols_b, figure="9")]
    relation, _, by = relation.partition(" by ")
    check = {"kind": "compare", "a": {"figure": "12"}, "b": {"figure": "9"}, "relation": relation}
    if by:
        check["by"] = float(by)
    if relation == "similar":
        check["within"] = 0.05
    assert evaluate_claim(claim(check), ds).verdict == expected


def test_compare_against_each_of_several_groups():
    ds = [panel(9, figure="15"), panel(4, figure="11"), panel(11, figure="14")]
    check = {
        "kind": "compare",
        "a": {"figure": "15"},
        "b": [{"figure": "11"}, {"figure": "14"}],
        "relation": "greater",
    }
    v = evaluate_claim(claim(check), ds)
    assert v.verdict == "fail"  # better than Fig. 11, worse than Fig. 14
    assert len(v.numbers["b"]) == 2


@pytest.mark.parametrize(
    "shares, direction, expected",
    [
        ((3, 6, 9), "increasing", "pass"),
        ((9, 6, 3), "increasing", "fail"),
        ((3, 3, 9), "increasing", "pass"),  # a flat step does not break a trend
        ((3, 9, 6), "increasing", "fail"),  # a step back beyond the resolution does
        ((5, 5, 5), "decreasing", "undecided"),
    ],
)
def test_trend(shares, direction, expected):
    ds = [panel(c, figure="19", row=r, mu=mu) for r, (c, mu) in enumerate(zip(shares, (0.25, 1.0, 5.0)), start=1)]
    check = {
        "kind": "trend",
        "select": {"figure": "19"},
        "along": "mu",
        "direction": direction,
        "label": "mu",
    }
    assert evaluate_claim(claim(check), ds).verdict == expected


def test_each_fills_open_attributes_only_and_combines_verdicts():
    ds = [panel(11, k=0), panel(11, k=1), panel(2, k=2)]
    check = {"kind": "stable_fraction", "select": {"figure": "9"}, "op": "==", "value": 1}
    assert evaluate_claim(claim(check, each={"k": [0, 1]}), ds).verdict == "pass"
    v = evaluate_claim(claim(check, each={"k": [0, 1, 2]}), ds)
    assert v.verdict == "fail" and set(v.numbers) == {"k = 0", "k = 1", "k = 2"}
    # b keeps its own k = 0, a gets each k
    cmp = {"kind": "compare", "a": {"figure": "9"}, "b": {"figure": "9", "k": 0}, "relation": "less"}
    v = evaluate_claim(claim(cmp, each={"k": [2]}), ds)
    assert v.verdict == "pass"


# -- parsing ------------------------------------------------------------------------------------

GOOD_CHECK = {"kind": "stable_fraction", "select": {"figure": "9"}, "op": "<", "value": 1}


@pytest.mark.parametrize(
    "item, message",
    [
        ({"colour": "red"}, "unknown key"),
        ({"check": {"kind": "nonsense"}}, "check.kind"),
        ({"reference": "maybe"}, "reference"),
        ({"each": {"k": 1}}, "each"),
        # the check's own parameters are checked against its function when the file is read
        ({"check": {**GOOD_CHECK, "opp": "<"}}, r"x.*unknown key.*opp"),
        ({"check": {k: v for k, v in GOOD_CHECK.items() if k != "value"}}, r"x.*lacks \['value'\]"),
        ({"check": {**GOOD_CHECK, "op": "=<"}}, r"x.*check.op must be one of"),
        ({"check": {**GOOD_CHECK, "region": {"lr": [0, 1]}}}, r"x.*region.*lr"),
        ({"check": {"kind": "compare", "a": {}, "b": {}, "relation": "bigger"}}, r"x.*check.relation"),
        ({"check": {"kind": "compare", "a": {}, "b": {}, "relation": "similar"}}, r"x.*within"),
        ({"check": {"kind": "trend", "select": {}, "along": "row", "direction": "up"}}, r"x.*check.direction"),
    ],
)
def test_parse_claims_names_the_bad_key(item, message):
    base = {
        "id": "x",
        "source": "s",
        "statement": "t",
        "figures": ["9"],
        "check": GOOD_CHECK,
    }
    parse_claims([base])  # the base itself is well formed
    with pytest.raises(ParameterError, match=message):
        parse_claims([{**base, **item}])


def test_parse_claims_rejects_duplicates_and_missing_keys():
    check = {"kind": "trend", "select": {}, "along": "row", "direction": "increasing"}
    base = {"id": "x", "source": "s", "statement": "t", "figures": ["9"], "check": check}
    with pytest.raises(ParameterError, match="duplicate"):
        parse_claims([base, base])
    with pytest.raises(ParameterError, match="missing"):
        parse_claims([{k: v for k, v in base.items() if k != "source"}])


# -- the stability claims file -------------------------------------------------------------------


def _listed(value):
    return value if isinstance(value, list) else [value]


def test_stability_claims_file_is_consistent_with_the_configuration():
    claims = load_claims(CLAIMS_FILE)
    cfg = yaml.safe_load(CONFIG_FILE.read_text())["stability"]
    figures = cfg["figures"]
    assert {c.check["kind"] for c in claims} <= set(CHECKS)
    for c in claims:
        assert set(c.figures) <= set(figures), c.id
        assert c.reference in ("pass", "fail", "undecided"), f"{c.id}: no full-resolution reference verdict"
        # every selector names configured figures (one or a list; a selector naming none reads the claim's
        # figures), computed with the scheme it selects (its own, from `each`, or the default: Jacobi), and
        # its rows / k / view exist there
        check = c.check
        selectors = [check[key] for key in ("select", "a") if key in check]
        b = check.get("b", [])
        selectors += b if isinstance(b, list) else [b]
        for sel in selectors:
            named = [str(f) for f in _listed(sel["figure"])] if "figure" in sel else list(c.figures)
            assert named, c.id
            for number in named:
                assert number in figures, f"{c.id}: Fig. {number} is not configured"
                fig = figures[number]
                schemes = dict(figure_schemes(number, fig))
                selected = _listed(sel["scheme"]) if "scheme" in sel else c.each.get("scheme", [DEFAULTS["scheme"]])
                rows = _listed(sel["row"]) if "row" in sel else c.each.get("row", [])
                for scheme in selected:
                    assert scheme in schemes, f"{c.id}: Fig. {number} is not computed with {scheme}"
                    for row in rows:
                        assert 1 <= row <= len(fig["rows"]), c.id
                        assert schemes[scheme] is None or row in schemes[scheme], c.id
                for k in _listed(sel["k"]) if "k" in sel else c.each.get("k", []):
                    assert k in fig["k"], c.id
                if sel.get("view") == "zoom":
                    assert fig.get("zoom"), f"{c.id}: Fig. {number} has no zoom panels"


def test_the_claims_cover_the_papers_statements():
    ids = {c.id for c in load_claims(CLAIMS_FILE)}
    for needed in (
        "fig10_k2_unstable_near_origin",
        "fig15_k0_only_stable",
        "fig18_k12_no_stable_point",
        "fig16_k12_unstable_near_origin",
        "fd_vs_ff_baumgarte_k0",
        "fd_vs_ff_baumgarte_k12",
        "fig11_projection_shrinks_with_alr21",
        "fig11_projection_shrinks_with_ali21",
        "fig19_k0_smaller_mu_more_stable",
        "fig19_k12_larger_mu_more_stable",
        "fig20_k0_smaller_ab_more_stable",
        "fig20_k12_larger_ab_more_stable",
    ):
        assert needed in ids


# -- end to end on engine data ----------------------------------------------------------------------


def test_index3_claim_on_a_coarse_engine_panel():
    """Sect. 3.5 on real (coarse) data: index 3 is stable at k = 0 and never at k = 1.  (21 x 21: the marginal
    undamped column, 1/21 of the points, cannot turn the 90 % of fig18_k0_good, as the 1/6 of a 6 x 6 grid would.)"""
    cfg = yaml.safe_load(CONFIG_FILE.read_text())["stability"]
    coarse = {"lr1": [-2.0, 0.0], "li1": [0.0, 2.0], "n": 21}
    specs = figure_panels(
        "18", cfg["figures"]["18"], grid=coarse, zoom_grid=coarse, precision={"policy": "auto", "digits": 30}
    )
    datasets = [stability_panel(s) for s in specs if s.k in (0, 1)]
    by_id = {c.id: c for c in load_claims(CLAIMS_FILE)}
    verdicts = {v.claim.id: v for v in evaluate([by_id["fig18_k12_no_stable_point"], by_id["fig18_k0_good"]], datasets)}
    # k = 2 has no data here: the `each` over k = 1, 2 cannot pass as a whole
    assert verdicts["fig18_k12_no_stable_point"].verdict == "undecided"
    assert "[k = 1]" in verdicts["fig18_k12_no_stable_point"].measured
    assert "-> pass" in verdicts["fig18_k12_no_stable_point"].measured.split(";")[0]
    assert verdicts["fig18_k0_good"].verdict == "pass"
    # the same machinery reports a failure when the data contradict the check
    contrary = claim({"kind": "stable_fraction", "select": {"figure": "18", "k": 0}, "op": "==", "value": 0})
    assert evaluate_claim(contrary, datasets).verdict == "fail"


def test_spec_is_plain_data():
    spec = PanelSpec(
        figure="9",
        row=1,
        k=0,
        view="full",
        method="projection",
        method_params={},
        decomposition="dd",
        am21=1,
        alr21=1,
        ali21=1,
        lr1=(-2, 0),
        li1=(0, 2),
        n=3,
    )
    assert PanelSpec.from_params(spec.as_dict()) == spec


# -- one mechanism for every part -------------------------------------------------------------------

PART_FILES = {part: ROOT / "config" / "claims" / f"{part}.yaml" for part in ("stability", "convergence", "pendulum")}
PART_KINDS = {
    "stability": {"stable_fraction", "compare", "trend", "pointwise"},
    "convergence": {"convergence_order"},
    "pendulum": {"pendulum_stability"},
}


@pytest.mark.parametrize("part", sorted(PART_FILES))
def test_every_claims_file_parses_with_the_one_parser(part):
    doc = yaml.safe_load(PART_FILES[part].read_text())
    claims = load_claims(PART_FILES[part])
    assert [c.id for c in claims] == [item["id"] for item in doc["claims"]]
    assert {c.check["kind"] for c in claims} <= PART_KINDS[part]
    for c, item in zip(claims, doc["claims"]):
        assert c.statement == item["statement"] and c.source == item["source"] and c.note == item.get("note", "")


@pytest.mark.parametrize(
    "part, change, key",
    [
        ("stability", lambda c: c.update(colour="red"), "colour"),
        ("stability", lambda c: c["check"].update(valeu=1), "valeu"),
        ("convergence", lambda c: c.update(colour="red"), "colour"),
        ("convergence", lambda c: c["check"]["expect"][0].update(ordre=2), "ordre"),
        ("convergence", lambda c: c.update(ci="yes"), "ci"),
        ("pendulum", lambda c: c.update(colour="red"), "colour"),
        ("pendulum", lambda c: c["check"].update(default="fine"), "default"),
        ("pendulum", lambda c: c["check"]["exceptions"][0].update(expected="wobbly"), r"exceptions\[0\]\.expected"),
        ("pendulum", lambda c: c["check"].update(kind="divergence"), "check.kind"),
    ],
)
def test_a_malformed_claim_in_any_file_is_refused_naming_id_and_key(tmp_path, part, change, key):
    doc = yaml.safe_load(PART_FILES[part].read_text())
    item = doc["claims"][-1]
    change(item)
    path = tmp_path / "claims.yaml"
    path.write_text(yaml.safe_dump(doc))
    with pytest.raises(ParameterError, match=rf"\({item['id']}\).*{key}"):
        load_claims(path)


def test_unknown_top_level_key_is_refused(tmp_path):
    doc = yaml.safe_load(PART_FILES["convergence"].read_text())
    path = tmp_path / "claims.yaml"
    path.write_text(yaml.safe_dump({**doc, "tolerance": 0.25}))
    with pytest.raises(ParameterError, match="unknown top-level key.*tolerance"):
        load_claims(path)


def test_writer_references_and_table(tmp_path):
    """JSON/TSV written from the verdicts; a ci claim off its reference stops the job; the table shows both."""
    ds = [panel(5, k=0)]
    good = claim({**GOOD_CHECK}, ci=True, reference="pass")  # 5 of 11 columns stable: "< 1" holds
    off = parse_claims(
        [
            {
                "id": "d",
                "source": "s",
                "statement": "t",
                "figures": ["9"],
                "check": GOOD_CHECK,
                "ci": True,
                "reference": "fail",
            }
        ]
    )[0]
    verdicts = evaluate([good, off], ds)
    assert [v.verdict for v in verdicts] == ["pass", "pass"]
    assert [v.claim.id for v in reference_mismatches(verdicts)] == ["d"]
    enforce_references(verdicts, False)  # not enforced: no error
    with pytest.raises(SystemExit, match="d: verdict pass, reference fail"):
        enforce_references(verdicts, True)
    records = write_verdicts(verdicts, tmp_path / "c.json", tmp_path / "c.tsv")
    assert read_verdicts(tmp_path / "c.json") == records
    assert records[0]["numbers"]["Fig. 9 row 1 k=0"]["n_stable"] == 5 * 11
    tsv = (tmp_path / "c.tsv").read_text().splitlines()
    assert tsv[0].split("\t")[:5] == ["id", "source", "figures", "statement", "verdict"]
    assert tsv[2].split("\t")[4:6] == ["pass", "fail"]
    html = claims_table(records, note_header="how read")
    assert "NOT reproduced" in html and "how read" in html and html.count('class="pass"') == 2


def _with_verdicts(ds, marginal_cols):
    """The synthetic panel with verdicts: its last ``marginal_cols`` lr1 columns marginal (neither stable nor
    unstable), as certification reports points whose proven enclosure contains 1."""
    verdict = np.where(ds["stable"].values, 0, 1).astype(np.int8)
    verdict[-marginal_cols:, :] = 2
    return ds.assign(
        verdict=(("lr1", "li1"), verdict),
        stable=(("lr1", "li1"), verdict == 0),
        certified=(("lr1", "li1"), verdict == 2),
    )


def test_marginal_points_make_a_share_an_interval():
    ds = _with_verdicts(panel(4, n=11), 1)  # the undamped column lr1 = 0 marginal
    share = stable_share(ds)
    assert (share.stable, share.open, share.certified) == (44, 11, 11)
    assert share.low == pytest.approx(44 / 121) and share.high == pytest.approx(55 / 121)


def test_a_claim_the_marginal_points_could_turn_is_undecided():
    """'Only stable points' on a panel whose unstable-or-stable status rests on marginal points: undecided, and
    it says how many points are certified and marginal; excluding them decides it."""
    ds = _with_verdicts(panel(10, n=11), 1)  # every damped point stable, the undamped column marginal
    c = claim({"kind": "stable_fraction", "select": {"figure": "9"}, "op": "==", "value": 1})
    v = evaluate([c], [ds])[0]
    assert v.verdict == "undecided" and "11 marginal" in v.measured and "121 points used: 11 certified" in v.measured
    c2 = claim(
        {
            "kind": "stable_fraction",
            "select": {"figure": "9"},
            "op": "==",
            "value": 1,
            "region": {"exclude_undamped": True},
        }
    )
    assert evaluate([c2], [ds])[0].verdict == "pass"


def test_compare_with_marginal_points_decides_only_beyond_them():
    a = _with_verdicts(panel(8, n=11, row=2), 1)  # share 88/121 ... 99/121
    b = panel(2, n=11, row=1)  # share 22/121
    c = claim({"kind": "compare", "a": {"row": 2}, "b": {"row": 1}, "relation": "greater"})
    assert evaluate([c], [a, b])[0].verdict == "pass"  # greater for every way the marginal points go
    b_close = panel(9, n=11, row=1)  # 99/121: a is less only if none of its marginal points is stable
    assert evaluate([c], [a, b_close])[0].verdict == "undecided"
