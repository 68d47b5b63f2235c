"""The report's sections and page (icosim.report) built from small synthetic inputs.

Every assertion checks content that follows from the inputs given here: counts, labels,
numbers and the figures embedded, not the wording around them.
"""

import base64
import hashlib
import io
import json
import re

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

from icosim.report.claims import claims_table
from icosim.report.convergence import convergence_section
from icosim.report.html import table
from icosim.report.page import report_page
from icosim.report.pendulum import pendulum_section
from icosim.report.stability import overturned_html, stability_section


@pytest.fixture(scope="module")
def png(tmp_path_factory):
    path = tmp_path_factory.mktemp("fig") / "fig9.png"
    fig = Figure(figsize=(1, 1))
    fig.subplots().plot([0, 1], [1, 0])
    fig.savefig(path, format="png", dpi=20)
    return path


def record(cid, verdict, reference=None, **extra):
    return {
        "id": cid,
        "source": "Sect. 3.1",
        "statement": f"statement of {cid}",
        "figures": ["9"],
        "verdict": verdict,
        "reference": reference,
        "matches_reference": None if reference is None else reference == verdict,
        "measured": f"measured {cid}",
        "note": f"note {cid}",
        "numbers": {},
        **extra,
    }


def test_claims_table_marks_verdicts_and_references():
    html = claims_table([record("a", "pass", "pass"), record("b", "fail", "pass"), record("c<", "undecided")])
    assert html.count("<tr>") == 4  # header and three claims
    assert '<span class="pass">pass</span> (full-resolution reference: pass, reproduced)' in html
    assert "NOT reproduced at this resolution" in html and "c&lt;" in html  # escaped
    assert table(["x"], [["<b>"]], raw_columns=(0,)).endswith("<td><b></td></tr></tbody></table>")


STABILITY_FIGURE = {
    "title": "Baumgarte index 1, ff",
    "method": "baumgarte",
    "decomposition": "ff",
    "params": {"index": 1, "mu": 1.0},
    "ratios": {"am21": 1.0, "alr21": 1.0, "ali21": 1.0},
    "rows": [{}, {"am21": 5.0}],
    "k": [0, 1],
}
GRID = {"lr1": [-2.0, 0.0], "li1": [0.0, 2.0], "n": 21}
ZOOM = {"lr1": [-0.2, 0.0], "li1": [0.0, 0.2], "n": 11}


def panel_attrs(row, k, hp, overturned=()):
    return {
        "figure": "9",
        "row": row,
        "k": k,
        "view": "full",
        "n_points": 441,
        "n_high_precision": hp,
        "n_high_precision_undamped": hp // 2,
        "n_certified": hp,
        "n_marginal": hp // 5,
        "n_audited": 4,
        "n_overturned": len(overturned),
        "overturned_points": json.dumps(list(overturned)),
        "cpu_seconds_float64": 1.5,
        "cpu_seconds_certify": 0.5,
        "cpu_seconds_mp": 0.0,
    }


def test_stability_section_counts_precision_claims_and_figures(png):
    attrs = [panel_attrs(r, k, hp) for r, k, hp in ((1, 0, 10), (1, 1, 20), (2, 0, 30), (2, 1, 40))]
    html = stability_section(
        figures={"9": STABILITY_FIGURE},
        grid=GRID,
        zoom_grid=ZOOM,
        precision={"policy": "auto", "digits": 64},
        style="field",
        decisions=["because <reasons>"],
        panel_attrs=attrs,
        claims=[record("a", "pass"), record("b", "fail"), record("c", "undecided")],
        figure_pngs=[str(png)],
    )
    assert html.startswith('<section id="stability">')
    assert "100 of 1764 grid points (5.67%) were certified, 20 of them marginal, 50 on the undamped axis" in html
    assert "(2 of 8 CPU-seconds in 4 panel jobs" in html and "took 25% of the sweeps' compute time" in html
    # no float64 verdict overturned: said, with the count of points checked
    assert "Overturned float64 verdicts: none.</b> 16 points that float64 decided were also certified" in html
    assert "3 claims" in html and "1 pass, 1 fail, 1 undecided" in html
    assert "raise αm21, αλr21, αλi21 in turn to 5." in html and "because &lt;reasons&gt;" in html
    assert "row 2: αm21 = 5, αλr21 = 1, αλi21 = 1" in html  # row labels from the configuration
    assert "at 128 bits, where undecided once more at 1024" in html and "21 × 21 points" in html
    assert same_pixels(embedded_images(html)[0], png.read_bytes())  # the figure itself, embedded
    assert '<figure id="stability-fig9" data-paper-figures="9">' in html
    assert '<tr id="stability-claim-b">' in html and 'Used by claims: <a href="#stability-claim-a">a</a>' in html


def embedded_images(html) -> list:
    """The bytes of every data-URI image of a page."""
    return [base64.b64decode(m) for m in re.findall(r'src="data:image/[a-z+]+;base64,([^"]+)"', html)]


def same_pixels(a: bytes, b: bytes) -> bool:
    from PIL import Image

    with Image.open(io.BytesIO(a)) as x, Image.open(io.BytesIO(b)) as y:
        return x.size == y.size and np.array_equal(np.asarray(x.convert("RGB")), np.asarray(y.convert("RGB")))


def test_stability_section_lists_every_overturned_float64_verdict():
    point = {
        "lr1": -0.5,
        "li1": 0.25,
        "float64_verdict": "stable",
        "verdict": "unstable",
        "rho_lower": 1.000001,
        "rho_upper": 1.000002,
    }
    html = overturned_html([panel_attrs(1, 0, 10), panel_attrs(2, 1, 10, overturned=[point])])
    assert "Overturned float64 verdicts: 1</b> of 8 points checked" in html
    assert "<td>Fig. 9 row 2 k = 1 (full)</td><td>-0.5</td><td>0.25</td><td>stable</td><td>unstable</td>" in html
    assert "[1.000001, 1.000002]" in html


def _convergence_inputs(tmp_path):
    from icosim.studies.convergence.datasets import run_panel
    from icosim.studies.convergence.experiment import Setup, step_counts
    from icosim.studies.convergence.panels import PanelSpec
    from icosim.studies.convergence.study import Study
    from icosim.studies.convergence.work_precision import resolve_configuration, work_precision

    setup = Setup(end_time=0.2)
    steps = {"H_min": 2e-4, "H_max": 2e-2, "num": 5}
    study = Study(setup, step_counts(0.2, steps["H_min"], steps["H_max"], steps["num"]))
    fit = {"decades": 1.0, "tolerance": 0.1, "min_points": 2}
    spec = PanelSpec("23", "ff", "all", "projection", {}, ({},), (0, 1))
    ds = run_panel(spec, study, fit)
    fig = {"title": "projection", "method": "projection", "columns": [{}], "rows": [{}], "decompositions": ["ff"]}
    entries = resolve_configuration({"figure": "23"}, {"23": fig}, [0, 1])
    wp = work_precision(entries, {(spec.scheme, "ff", "23", "all"): ds}, setup, steps=1, repeats=1, warmup_steps=0)
    return setup, steps, fig, ds, wp


def test_convergence_section_reports_curves_claims_and_work_precision(tmp_path, png):
    setup, steps, fig, ds, wp = _convergence_inputs(tmp_path)
    row = {
        "curve": "ff, projection, k = 0",
        "claimed": "O(H^2)",
        "order": float(ds["order"].values[0, 0]),
        "order_status": str(ds["order_status"].values[0, 0]),
        "reason": str(ds["fit_note"].values[0, 0]),
        "fit_H_min": 2e-4,
        "fit_H_max": 2e-2,
        "local_slopes": [1.9, 2.1],
        "order_second_half": float("nan"),
        "order_startup": 3.5,
        "stable_H": "all",
        "verdict": "pass",
    }
    claim = record("proj", "pass", numbers={"rows": [row], "tolerance": 0.3})
    fig_png = tmp_path / "fig23_ff_jacobi.png"  # results/convergence/figures/fig<figure>_<dec>_<scheme>.png
    fig_png.write_bytes(png.read_bytes())
    (tmp_path / "fig23_ff_jacobi_slopes.png").write_bytes(png.read_bytes())
    html = convergence_section(
        setup=setup.as_dict(),
        step_sizes=steps,
        stepping="error",
        fit={"decades": 1.0, "tolerance": 0.1, "min_points": 2},
        startup_steps=7,
        unstable={"growth_bound": 1e3, "spectral_policy": "auto", "digits": 128},
        targets=[1e-2],
        figures={"23": fig},
        panels=[ds],
        claims=[claim],
        figure_pngs=[str(fig_png)],
        wp=wp,
        wp_png=str(png),
    )
    assert html.startswith('<section id="convergence">')
    assert "2 curves in 1 panel datasets" in html  # k = 0, 1 of one row
    assert f"{len(study_H(ds))} sizes H = T/N_total from 0.0002 s to 0.02 s" in html
    assert "1 claims (config/claims/convergence.yaml)" in html and "within ±0.3 of the claim" in html
    assert f"{row['order']:.2f} on [0.0002, 0.02] s" in html and "1.90 … 2.10" in html
    assert f"<td>{row['order_status']}" in html and "<td>3.50</td>" in html  # status and start-up order per curve
    assert "within ±0.1 of it" in html and "first 7 macro steps" in html  # the decision rule and start-up window
    assert "no round-off floor" in html and f"proven at {int(ds['defect_bits'].max())} bits" in html
    assert "<b>Fig. 23, ff</b> (as in the paper)" in html and html.count('class="pair"') == 1
    for configuration in wp["configuration"].values:  # the work-precision curves are configurations
        assert str(configuration) in html or str(configuration).split(" ", 1)[1] in html


def study_H(ds):
    return ds["H"].values


def pendulum_summary():
    runs = ["baumgarte_ff_k0", "weighted_ff_k2"]
    ds = xr.Dataset(
        {
            "status": ("run", ["stable", "diverged"]),
            "reason": ("run", ["none", "|lambda_c| > 1000.0 N"]),
            "diverged": ("run", [0, 1]),
            "failed": ("run", [0, 0]),
            "t_diverged": ("run", [np.nan, 0.205]),
            "t_failed": ("run", [np.nan, np.nan]),
            "t_last": ("run", [0.5, 0.204]),
            "err_phi1": ("run", [1e-6, 2e-2]),
            "err_phi2": ("run", [2e-6, 3e-2]),
            "err_lambda": ("run", [1e-3, 5.0]),
            "max_g": ("run", [1e-9, 1e-3]),
            "max_g_corrector": ("run", [2e-9, 2e-3]),
            "wall_time_s": ("run", [1.0, 2.0]),
            "observed": ("run", ["stable", "unstable"]),
            "rho_test_model": ("run", [0.99, 1.13]),
            "expected_sect4": ("run", ["stable", "unstable"]),
            "verdict_sect4": ("run", ["pass", "pass"]),
        },
        coords={
            "run": ("run", runs),
            "method": ("run", ["baumgarte", "weighted"]),
            "decomposition": ("run", ["ff", "ff"]),
            "k": ("run", [0, 2]),
        },
    )
    ds.attrs.update(
        test_model_lr1=[-1e-3, -1e-3], test_model_li1=[3e-3, 7e-3], test_model_ratios="am21 = 1, alr21 = 1, ali21 = 1"
    )
    return ds


def test_pendulum_section_lists_every_run(tmp_path, png):
    import yaml
    from helpers import ROOT

    cfg = yaml.safe_load((ROOT / "config" / "pendulum.yaml").read_text())["pendulum"]
    k_png = tmp_path / "pendulum_k2_jacobi.png"  # results/pendulum/figures/pendulum_k<k>_<scheme>.png
    k_png.write_bytes(png.read_bytes())
    html = pendulum_section(
        config=cfg,
        paper_figure={2: 8},
        summary=pendulum_summary(),
        claims=[record("sect4", "pass")],
        figure_pngs=[str(k_png)],
        error_png=str(png),
    )
    assert html.startswith('<section id="pendulum">')
    assert "1 of 2 runs diverged, 0 failed" in html and "earliest divergence is at\nt = 0.205 s" in html
    assert "Claim <b>sect4</b>, run by run" in html
    assert "<td>weighted</td><td>ff</td><td>2</td><td>unstable</td><td>unstable</td>" in html
    assert "1.130000" in html and "2.00e-02" in html  # rho_test and the error of the diverged run
    assert "Fig. 8 of the paper (k = 2)" in html


def test_page_orders_sections_and_hashes_the_configuration(tmp_path):
    cfg = tmp_path / "config.yaml"
    cfg.write_text("report: {}\n")
    html = report_page(
        title="T <1>",
        parts=["b", "a"],
        skipped=["c"],
        sections=["<section id='b'>B</section>", "<section id='a'>A</section>"],
        configfiles=[str(cfg)],
        config_sha256={"report": "abc"},
        precision={"policy": "auto", "digits": 128},
        commit_text="0123",
        generated="2000-01-01T00:00:00+00:00",
    )
    assert html.index("B</section>") < html.index("A</section>") and "<title>T &lt;1&gt;</title>" in html
    assert '<li><a href="#b">b</a></li><li><a href="#a">a</a></li>' in html
    assert hashlib.sha256(cfg.read_bytes()).hexdigest() in html and "<code>abc</code>" in html
    assert "parts without a section (not built): c" in html and "git commit: <code>0123</code>" in html


def test_summary_first_counts_verdicts_and_links_each_disagreement(tmp_path, png):
    note = "Read as shares.  Disagreement (the data stand): fd is less stable than ff, e.g. in Fig. 9.  More text."
    stab = [record("a", "pass"), record("b", "fail", note=note), record("c", "undecided")]
    pend = [record("sect4", "pass", figures=["6", "7", "8"])]
    section = stability_section(
        figures={"9": STABILITY_FIGURE},
        grid=GRID,
        zoom_grid=ZOOM,
        precision={"policy": "auto", "digits": 64},
        style="field",
        decisions=[],
        panel_attrs=[panel_attrs(1, 0, 1)],
        claims=stab,
        figure_pngs=[str(png)],
    )
    cfg = tmp_path / "config.yaml"
    cfg.write_text("report: {}\n")
    html = report_page(
        title="T",
        parts=["stability", "pendulum"],
        skipped=[],
        sections=[section, "<section id='pendulum'>P</section>"],
        configfiles=[str(cfg)],
        config_sha256={},
        precision={"policy": "auto", "digits": 128},
        commit_text="0",
        generated="now",
        claims={"stability": stab, "pendulum": pend},
    )
    assert html.index('<section id="summary">') < html.index('<section id="stability">')  # the answer first
    summary = html[html.index('<section id="summary">') : html.index('<section id="stability">')]
    assert "<td>3</td><td>1</td><td>1</td><td>1</td>" in summary  # stability: 3 claims, 1 / 1 / 1
    assert "<td>all</td><td>4</td><td>2</td><td>1</td><td>1</td>" in summary
    # the disagreement: the note's own sentence, and links to the claim row, the figure and the dataset
    assert "<i>Why:</i> Disagreement (the data stand): fd is less stable than ff, e.g. in Fig. 9." in summary
    assert '<a href="#stability-claim-b">b</a>' in summary and '<a href="#stability-fig9">Fig. 9</a>' in summary
    # a claim that names no scheme reads Jacobi's panels: the link goes to them
    assert '<a href="../results/stability/fig9/jacobi/"><code>results/stability/fig9/jacobi/</code></a>' in summary
    assert "Undecided" in summary and '<a href="#stability-claim-c">c</a>' in summary
    assert "full-resolution reference" not in summary  # no claim here has a reference
    assert '<li><a href="#summary">summary</a></li>' in html


def test_long_claim_texts_fold_away():
    long = "word " * 60
    html = claims_table([record("a", "pass", statement=long, note="short note")], part="p")
    assert html.count("<details>") == 1 and "<summary>word word" in html and "short note" in html
