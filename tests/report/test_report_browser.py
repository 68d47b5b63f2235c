"""The report in a real browser: headless Chromium (Debian's ``chromium``) via icosim.report.browser.

* a small report built here from a real stability panel, figure and claims (always);
* the workflow's report ``reports/icosim_report.html`` when it exists (in CI the workflow runs
  first): then its screenshot is the CI artifact ``results/report_screenshot.png`` and its size
  and load time go to ``results/report_check.json``;
* a broken page, to show the check finds console errors, undecodable images and dead links.

The tests are marked ``browser``: without Chromium they are skipped (tests/toolchains.py; CI installs it and
requires it).
"""

import json

import pytest
from helpers import ROOT

from icosim.report import browser

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def chromium():
    return browser.find_chromium()


def assert_clean(result):
    assert result["errors"] == [], result["errors"]
    assert result["images"] and all(i["ok"] for i in result["images"]), result["images"]
    assert all(i["ok"] and i["width"] > 0 for i in result["static"]["images"] if i["kind"] != "svg")
    assert result["links"] and all(link["ok"] for link in result["links"]), [
        link for link in result["links"] if not link["ok"]
    ]
    assert all(link["ok"] for link in result["static"]["links"])


@pytest.fixture(scope="module")
def small_report(tmp_path_factory):
    """A report page from a real (small) panel, its figure, a section and claims, one of them failing."""
    from icosim.figures import save_figure
    from icosim.figures.stability import stability_figure
    from icosim.report.page import report_page
    from icosim.report.stability import stability_section
    from icosim.studies.stability.datasets import stability_panel
    from icosim.studies.stability.panels import figure_panels

    tmp = tmp_path_factory.mktemp("report")
    cfg = {
        "title": "weighted multiplier, ff",
        "method": "weighted",
        "decomposition": "ff",
        "params": {"a": 1.0, "b": 1.0},
        "ratios": {"am21": 1.0, "alr21": 1.0, "ali21": 1.0},
        "rows": [{}],
        "k": [0, 2],
    }
    grid = {"lr1": [-2.0, -0.02], "li1": [0.0, 2.0], "n": 9}
    precision = {"policy": "float64", "digits": 128}
    specs = figure_panels("10", cfg, grid=grid, zoom_grid=grid, precision=precision)
    panels = [stability_panel(s) for s in specs]
    png = tmp / "fig10.png"
    save_figure(stability_figure(panels, title="Fig. 10"), png)

    def claim(cid, verdict, note):
        return {
            "id": cid,
            "source": "Sect. 3.1.2",
            "statement": "A statement long enough to fold away. " * 8,
            "figures": ["10"],
            "verdict": verdict,
            "reference": None,
            "matches_reference": None,
            "measured": "measured",
            "note": note,
            "numbers": {},
        }

    claims = [claim("holds", "pass", "fine"), claim("differs", "fail", "Disagreement (the data stand): it differs.")]
    section = stability_section(
        figures={"10": cfg},
        grid=grid,
        zoom_grid=grid,
        precision=precision,
        style="field",
        decisions=["a decision"],
        panel_attrs=[p.attrs for p in panels],
        claims=claims,
        figure_pngs=[str(png)],
    )
    conf = tmp / "config.yaml"
    conf.write_text("report: {}\n")
    html = report_page(
        title="icosim report (test)",
        parts=["stability"],
        skipped=[],
        sections=[section],
        configfiles=[str(conf)],
        config_sha256={"stability": "0" * 64},
        precision=precision,
        commit_text="test",
        generated="2000-01-01T00:00:00+00:00",
        claims={"stability": claims},
    )
    path = tmp / "reports" / "icosim_report.html"
    path.parent.mkdir()
    path.write_text(html, encoding="utf-8")
    return path


def test_small_report_in_chromium(chromium, small_report, tmp_path):
    result = browser.check_report(small_report, screenshot_path=tmp_path / "top.png", chromium=chromium)
    assert_clean(result)
    hrefs = {link["href"] for link in result["links"]}
    assert {"#summary", "#stability", "#stability-fig10", "#stability-claim-differs"} <= hrefs
    assert (tmp_path / "top.png").stat().st_size > 0


def test_broken_page_is_caught(chromium, tmp_path):
    page = tmp_path / "broken.html"
    page.write_text(
        "<!DOCTYPE html><html><head><title>b</title></head><body><a href='#gone'>x</a>"
        "<img alt='bad' src='data:image/png;base64,AAAA'><script>console.error('boom')</script></body></html>"
    )
    result = browser.check_report(page, chromium=chromium)
    assert any("boom" in e for e in result["errors"]) and any("failed to load" in e for e in result["errors"])
    assert not result["images"][0]["ok"] and not result["static"]["images"][0]["ok"]
    assert result["links"] == [{"href": "#gone", "ok": False}]


REPORT = ROOT / "reports" / "icosim_report.html"


@pytest.mark.skipif(not REPORT.exists(), reason="no workflow report (reports/icosim_report.html); CI builds it first")
def test_workflow_report_in_chromium(chromium):
    shot = ROOT / "results" / "report_screenshot.png"
    result = browser.check_report(REPORT, screenshot_path=shot, chromium=chromium)
    assert_clean(result)
    missing = [link["href"] for link in result["static"]["file_links"] if not link["exists"]]
    assert not missing, f"links to files that do not exist: {missing}"
    assert shot.stat().st_size > 0
    measured = {
        "bytes": result["static"]["bytes"],
        "load_ms": result["load_ms"],
        "chromium_wall_s": result["wall_s"],
        "images": len(result["images"]),
        "image_bytes": sum(i["bytes"] for i in result["static"]["images"]),
        "internal_links": len(result["links"]),
    }
    (ROOT / "results" / "report_check.json").write_text(json.dumps(measured, indent=1))
    print(f"\nreport: {measured['bytes'] / 1e6:.2f} MB, load {measured['load_ms']:.0f} ms (headless Chromium)")
