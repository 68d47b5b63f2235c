"""Size and load time of the report, and which image encoding is smallest per figure kind.

    python benchmarks/report_size.py [--report reports/icosim_report.html] [--results results] [--svg]

1. The page: bytes, embedded images by encoding, and the load time in headless Chromium
   (navigation timing ``loadEventStart``, best of ``--repeats`` runs; icosim.report.browser).
2. Per figure kind (stability, convergence, pendulum, work-precision): the bytes of the PNGs as
   matplotlib writes them, of their 256-colour palette version (what the report embeds where it
   is smaller: icosim.report.html.compact_png) and of lossless WebP; with ``--svg`` also of SVG,
   re-drawn from the datasets by the same figure builders (stability and pendulum figures).
"""

from __future__ import annotations

import argparse
import io
from collections import defaultdict
from pathlib import Path

from PIL import Image

from icosim.report import browser
from icosim.report.html import compact_png

KINDS = {
    "stability": "stability/figures/fig*.png",
    "convergence": "convergence/figures/fig*.png",
    "work-precision": "convergence/figures/work_precision.png",
    "pendulum": "pendulum/figures/*.png",
}


def webp(data: bytes) -> int:
    with Image.open(io.BytesIO(data)) as im:
        buf = io.BytesIO()
        im.save(buf, "WEBP", lossless=True, method=6)
    return buf.tell()


def svg_sizes(results: Path) -> dict:
    """SVG bytes of the stability and pendulum figures, re-drawn from their datasets."""
    from icosim.figures.pendulum import pendulum_figure
    from icosim.figures.stability import stability_figure
    from icosim.io.netcdf import open_dataset

    out = defaultdict(int)
    for folder in sorted((results / "stability").glob("fig*")):
        if folder.is_dir() and list(folder.glob("*.nc")):
            buf = io.BytesIO()
            stability_figure([open_dataset(p) for p in sorted(folder.glob("*.nc"))]).savefig(buf, format="svg")
            out["stability"] += buf.tell()
    runs_dir = results / "pendulum"
    if (runs_dir / "reference.nc").exists():
        runs = [open_dataset(p) for p in sorted(runs_dir.glob("*_k*.nc"))]
        reference = open_dataset(runs_dir / "reference.nc")
        for k in sorted({int(r.attrs["k"]) for r in runs}):
            buf = io.BytesIO()
            pendulum_figure([r for r in runs if int(r.attrs["k"]) == k], reference, k=k).savefig(buf, format="svg")
            out["pendulum"] += buf.tell()
    return dict(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--report", default="reports/icosim_report.html")
    ap.add_argument("--results", default="results")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--svg", action="store_true", help="also measure SVG (re-draws figures; slower)")
    args = ap.parse_args()
    report, results = Path(args.report), Path(args.results)

    if report.exists():
        static = browser.static_check(report)
        kinds = defaultdict(lambda: [0, 0])
        for i in static["images"]:
            kinds[i.get("kind", "?")][0] += 1
            kinds[i.get("kind", "?")][1] += i.get("bytes", 0)
        print(f"{report}: {static['bytes'] / 1e6:.2f} MB")
        for kind, (n, b) in kinds.items():
            print(f"  {n} {kind} images, {b / 1e6:.2f} MB decoded ({4 / 3 * b / 1e6:.2f} MB as base64)")
        if browser.find_chromium():
            loads = [browser.check_report(report)["load_ms"] for _ in range(args.repeats)]
            print(f"  load in headless Chromium: {min(loads):.0f} ms (best of {args.repeats}: {loads})")
        else:
            print("  (no Chromium: load time not measured)")

    print(f"\nfigures in {results} (bytes; what the report embeds is the smaller of png and palette):")
    print(f"  {'kind':<15}{'n':>3}{'png':>11}{'palette':>11}{'webp':>11}{'svg':>11}")
    svg = svg_sizes(results) if args.svg else {}
    for kind, pattern in KINDS.items():
        files = [p for p in sorted(results.glob(pattern)) if not (kind == "convergence" and "work_precision" in p.name)]
        if not files:
            continue
        raw = [p.read_bytes() for p in files]
        png = sum(len(r) for r in raw)
        pal = sum(len(compact_png(r)) for r in raw)
        wp = sum(webp(r) for r in raw)
        s = svg.get(kind)
        print(f"  {kind:<15}{len(files):>3}{png:>11}{pal:>11}{wp:>11}{s if s else '-':>11}")


if __name__ == "__main__":
    main()
