"""Compare two runs of the workflow: are their results the same?

    python tools/compare_results.py OLD NEW [--rerender [--configfile FILE ...]] [--allow-added NAME ...]
        [--tolerances] [--allow-new-files]

OLD and NEW are checkouts (or copies) that each hold ``results/`` and ``reports/`` of a run.
Every file under ``results/`` must exist in both and be equal:

* NetCDF: every variable and coordinate with the same dims, dtype and bytes (NaN-aware by
  construction: bitwise), the same variable attributes and global attributes -- except the
  VOLATILE ones below, which record when and how fast a job ran;
* JSON (claims): equal as parsed (verdicts, measured text, numbers); TSV and PDF: equal bytes;
* PNG: equal pixel arrays (and equal bytes, reported separately);
* HTML (report sections) and ``reports/icosim_report.html``: equal after the volatile parts
  are masked (numbers in timing phrases and timing table cells, the figures drawn from
  timings, the provenance section's time and commit); every masked difference is listed.

``--rerender`` additionally rebuilds, with NEW's code, the report sections, the report and
the work-precision figure from OLD's results (a copy of NEW's tree with OLD's results marked
up to date by ``snakemake --touch``, those outputs deleted and built again, nothing else
rerun) and requires them to be equal to
OLD's byte for byte (the report modulo its provenance section): the figures and the report
come from the same data by the same logic.  Exit status 0 if everything is equal.

``--allow-added NAME`` forgives what NEW *adds* under that name and nothing else: a global or
variable attribute, or a variable (coordinate), present in NEW only; the name in a variable's
``coordinates`` attribute; and a key of that name present only in NEW's ``config_json`` (at any
depth; ``config_sha256`` is then checked against NEW's own ``config_json`` instead).  Used to show
that adding the ``scheme`` attribute (the Gauss-Seidel scheme) left every Jacobi result as it was.

Every OLD file without a NEW counterpart and every NEW file without an OLD one is listed;
``--allow-new-files``: what NEW adds (files, claim ids) is listed as added, not as a difference.

``--tolerances`` compares within the replication speed target's tolerances instead of bitwise
(``tools/compare_tolerances.py``: rho, NRMSE, pendulum angles; verdicts, statuses and claims' verdicts
equal; other differences, figures and HTML are notes) and ends with a table per part.

    python tools/compare_results.py OLD NEW --tolerances --allow-new-files
"""

from __future__ import annotations

import argparse
import base64
import hashlib
import io
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import compare_tolerances as tol  # noqa: E402

#: Global attributes that record time and cost of a job, never its result.
VOLATILE_ATTRS = {
    "history",  # creation time
    "seconds_total",
    "seconds_mp",
    "seconds_float64",
    "cpu_seconds_total",
    "cpu_seconds_mp",
    "cpu_seconds_float64",
    "seconds_certify",
    "cpu_seconds_certify",
    "wall_time_s",
}
#: Variables that are timings (file name -> variables).
VOLATILE_VARIABLES = {
    "convergence/work_precision.nc": {"cpu_seconds_per_step", "cpu_seconds_per_simulated_second", "setup_seconds"},
    "pendulum/summary.nc": {"wall_time_s"},
    # the trade's cost measures, and what is chosen by them (the cheapest run per accuracy level)
    "pendulum/work_precision.nc": {
        "cpu_seconds",
        "monolithic_cpu_seconds",
        "cheapest_config",
        "cheapest_H",
        "cheapest_cpu_seconds",
        "monolithic_Radau_cpu_at_level",
        "monolithic_Radau_tol_at_level",
        "monolithic_DOP853_cpu_at_level",
        "monolithic_DOP853_tol_at_level",
    },
}
#: Figures drawn from timings (compared by --rerender instead).
VOLATILE_FIGURES = {"convergence/figures/work_precision.png", "convergence/figures/work_precision.pdf"}
#: Timing phrases in the report: the numbers in them are masked.
TIMING_PHRASES = [
    r"The rechecks took [^<]*?CPU-seconds",
    r"The certification took [^<]*?CPU-seconds",
    r"[\d.]+ s of compute",
]
#: Table columns holding timings (header text), masked in every row; and tables ranked by time.
TIMING_COLUMNS = {
    "float64 CPU s",
    "mp CPU s",
    "mp share of CPU",
    "certification CPU s",
    "its share of CPU",
    "wall [s]",
    "ms per macro step",
    "CPU s per simulated s",
    "at H (s)",
    "fastest scheme",
    "next two",
}
IMAGE = re.compile(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"')


def _drop_added(a, b, names):
    """``b`` without the keys in ``names`` that ``a`` lacks (recursively through mappings and lists)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return {k: _drop_added(a.get(k), v, names) for k, v in b.items() if k in a or k not in names}
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [_drop_added(x, y, names) for x, y in zip(a, b)]
    return b


def _nc(old: Path, new: Path, rel: str, problems: list, allow_added=(), notes=None):
    import h5py

    vol_vars = VOLATILE_VARIABLES.get(rel, set())
    allow_added = set(allow_added)
    with h5py.File(old, "r") as a, h5py.File(new, "r") as b:

        def attrs(obj):
            # netCDF4 writes text attributes as fixed-length strings, which h5py reads as bytes: compare them as text
            return {
                k: v.tolist() if isinstance(v, np.ndarray) else v.decode() if isinstance(v, bytes) else v
                for k, v in obj.attrs.items()
            }

        ga, gb = attrs(a), attrs(b)
        if allow_added and "config_json" in ga and "config_json" in gb and ga["config_json"] != gb["config_json"]:
            ja, jb = json.loads(ga["config_json"]), json.loads(gb["config_json"])
            if ja == _drop_added(ja, jb, allow_added):
                digest = hashlib.sha256(gb["config_json"].encode()).hexdigest()
                if gb.get("config_sha256") == digest:
                    ga["config_json"], ga["config_sha256"] = gb["config_json"], gb["config_sha256"]
                    if notes is not None:
                        notes.append(f"{rel}: config_json equal but for the added {sorted(allow_added)}")
        for key in sorted(set(ga) | set(gb)):
            if key in VOLATILE_ATTRS or (key in allow_added and key not in ga):
                continue
            if key not in ga or key not in gb or not _same(ga[key], gb[key]):
                problems.append(f"{rel}: global attribute {key!r}: {ga.get(key)!r} != {gb.get(key)!r}")
        na, nb = set(a.keys()), set(b.keys()) - (allow_added - set(a.keys()))
        if na != nb:
            problems.append(f"{rel}: variables differ: {sorted(na ^ nb)}")
        for name in sorted(na & nb):
            va, vb = a[name], b[name]
            if va.shape != vb.shape or va.dtype != vb.dtype:
                problems.append(f"{rel}:{name}: shape/dtype {va.shape} {va.dtype} != {vb.shape} {vb.dtype}")
                continue
            aa, ab = attrs(va), attrs(vb)
            aa.pop("DIMENSION_LIST", None), ab.pop("DIMENSION_LIST", None)
            aa.pop("REFERENCE_LIST", None), ab.pop("REFERENCE_LIST", None)
            for key in [k for k in ab if k in allow_added and k not in aa]:
                ab.pop(key)
            if "coordinates" in ab and allow_added:  # xarray names the non-dimension coordinates here
                kept = [c for c in str(ab["coordinates"]).split() if c not in allow_added or c in na]
                ab["coordinates"] = " ".join(kept)
                aa["coordinates"] = str(aa.get("coordinates", ""))
            if not _same(aa, ab):
                problems.append(f"{rel}:{name}: attributes differ: {aa} != {ab}")
            if name in vol_vars:
                continue
            xa, xb = np.asarray(va[()]), np.asarray(vb[()])
            if xa.dtype == object:  # variable-length strings: compare the strings, not the pointers
                text = lambda v: v.decode() if isinstance(v, bytes) else v  # noqa: E731
                same = [text(v) for v in xa.ravel().tolist()] == [text(v) for v in xb.ravel().tolist()]
            else:  # bitwise: NaNs, infinities and the sign of zero included
                same = xa.tobytes() == xb.tobytes()
            if not same:
                problems.append(f"{rel}:{name}: values differ")


def _same(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
        return True
    return type(a) is type(b) and a == b


def _pixels(data: bytes):
    import matplotlib.image

    return matplotlib.image.imread(io.BytesIO(data), format="png")


def _png(old: Path, new: Path, rel: str, problems: list, notes: list):
    a, b = old.read_bytes(), new.read_bytes()
    if a != b:
        notes.append(f"{rel}: PNG bytes differ (pixels compared)")
    pa, pb = _pixels(a), _pixels(b)
    if pa.shape != pb.shape or not np.array_equal(pa, pb):
        problems.append(f"{rel}: pixels differ")


def _mask_html(text: str, volatile_images=()) -> str:
    """Mask timings, figures drawn from timings and the provenance section."""

    def image(m):
        data = base64.b64decode(m.group(1))
        digest = hashlib.sha256(_pixels(data).tobytes()).hexdigest()[:16]
        return f'src="png:{digest}"'

    text = IMAGE.sub(image, text)
    for digest in volatile_images:
        text = text.replace(f'src="png:{digest}"', 'src="png:<drawn from timings>"')
    text = re.sub(r'<section id="provenance">.*?</section>', "<provenance/>", text, flags=re.S)
    for phrase in TIMING_PHRASES:
        text = re.sub(phrase, lambda m: re.sub(r"\d[\d.,]*%?", "#", m.group(0)), text)
    out = []
    for table in re.split(r"(<table>.*?</table>)", text, flags=re.S):
        if not table.startswith("<table>"):
            out.append(table)
            continue
        heads = re.findall(r"<th>(.*?)</th>", table)
        cols = [i for i, h in enumerate(heads) if h in TIMING_COLUMNS]

        def row(m, cols=cols):
            cells = re.findall(r"<td>(.*?)</td>", m.group(0), flags=re.S)
            for i in cols:
                if i < len(cells):
                    cells[i] = "#"
            return "<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>"

        out.append(re.sub(r"<tr><td>.*?</tr>", row, table, flags=re.S) if cols else table)
    return "".join(out)


def _wp_digests(root: Path):
    path = root / "results/convergence/figures/work_precision.png"
    return [hashlib.sha256(_pixels(path.read_bytes()).tobytes()).hexdigest()[:16]] if path.exists() else []


def _html(old: Path, new: Path, rel: str, problems: list, notes: list, old_root: Path, new_root: Path):
    a, b = old.read_text(), new.read_text()
    if a == b:
        return
    ma = _mask_html(a, _wp_digests(old_root))
    mb = _mask_html(b, _wp_digests(new_root))
    if ma != mb:
        i = (
            next(i for i, (x, y) in enumerate(zip(ma, mb)) if x != y)
            if ma[: len(mb)] != mb[: len(ma)]
            else min(len(ma), len(mb))
        )
        problems.append(
            f"{rel}: differs beyond timings near ...{ma[max(0, i - 120) : i + 80]!r} / {mb[max(0, i - 120) : i + 80]!r}"
        )
    else:
        notes.append(f"{rel}: equal once timings, figures drawn from timings and provenance are masked")


def compare(
    old_root: Path, new_root: Path, allow_added=(), *, tolerances=False, allow_new_files=False, stats=None
) -> tuple[list, list]:
    """(differences, notes) between OLD's and NEW's results; ``stats`` (:func:`compare_tolerances.new_stats`)
    collects the largest differences per part with ``tolerances``."""
    problems, notes = [], []
    stats = tol.new_stats() if stats is None else stats
    old_res, new_res = old_root / "results", new_root / "results"
    for side, res in (("OLD", old_res), ("NEW", new_res)):
        if not any(res.rglob("*.nc")):  # nothing to compare is no evidence of equality
            problems.append(f"{side} {res}: no datasets here (give the directory of a run, the one holding results/)")
    if problems:
        return problems, notes
    files_a = {p.relative_to(old_res).as_posix() for p in old_res.rglob("*") if p.is_file()}
    files_b = {p.relative_to(new_res).as_posix() for p in new_res.rglob("*") if p.is_file()}
    # a dataset's checksum sidecar (icosim.io.integrity) follows its bytes, timings included: the dataset is compared
    files_a = {f for f in files_a if not f.endswith(".nc.sha256")}
    files_b = {f for f in files_b if not f.endswith(".nc.sha256")}
    for rel in sorted(files_a - files_b):
        problems.append(f"{rel}: only in OLD")
    for rel in sorted(files_b - files_a):
        (notes if allow_new_files else problems).append(f"{rel}: only in NEW" + (" (added)" if allow_new_files else ""))
    counts = {}
    for rel in sorted(files_a & files_b):
        a, b, suffix = old_res / rel, new_res / rel, Path(rel).suffix
        counts[suffix] = counts.get(suffix, 0) + 1
        if Path(rel).name.startswith("claims") and suffix in (".json", ".tsv"):  # claims: verdict per claim id
            strict = not tolerances
            tol.compare_claims(a, b, rel, problems, notes, stats, strict=strict, allow_new=allow_new_files)
            if strict and (json.loads(a.read_text()) if suffix == ".json" else a.read_bytes()) != (
                json.loads(b.read_text()) if suffix == ".json" else b.read_bytes()
            ):
                problems.append(f"{rel}: {suffix[1:].upper()} differs")
            continue
        # with --tolerances only datasets can differ: figures, HTML and other files are notes
        found = notes if tolerances and suffix != ".nc" else problems
        for label in (rel,):
            if rel in VOLATILE_FIGURES:
                notes.append(f"{rel}: drawn from timings (checked by --rerender)")
            elif suffix == ".nc" and tolerances:
                volatile = VOLATILE_VARIABLES.get(rel, set())
                tol.compare_dataset(a, b, label, problems, notes, stats, VOLATILE_ATTRS, volatile)
            elif suffix == ".nc":
                _nc(a, b, label, problems, allow_added, notes)
            elif suffix == ".json":
                if json.loads(a.read_text()) != json.loads(b.read_text()):
                    found.append(f"{label}: JSON differs")
            elif suffix == ".png":
                _png(a, b, label, found, notes)
            elif suffix == ".html":
                _html(a, b, label, found, notes, old_root, new_root)
            elif a.read_bytes() != b.read_bytes():
                found.append(f"{label}: bytes differ")
    report = Path("reports/icosim_report.html")
    if (old_root / report).exists() and (new_root / report).exists():
        found = notes if tolerances else problems
        _html(old_root / report, new_root / report, str(report), found, notes, old_root, new_root)
    notes.insert(0, "compared: " + ", ".join(f"{n} {s or 'other'}" for s, n in sorted(counts.items())))
    return problems, notes


RERENDERED = [
    "stability_report_section",
    "convergence_report_section",
    "pendulum_report_section",
    "convergence_work_precision_figure",
    "report",
    "all",
]
REBUILT = [
    "results/report/stability.html",
    "results/report/convergence.html",
    "results/report/pendulum.html",
    "results/convergence/figures/work_precision.png",
    "results/convergence/figures/work_precision.pdf",
    "reports/icosim_report.html",
]


def rerender(old_root: Path, new_root: Path, snakemake_args: list) -> list:
    """NEW's code on OLD's results: report sections, report and work-precision figure as OLD's."""
    problems = []
    snakemake = str(Path(sys.executable).with_name("snakemake"))
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp) / "wf"
        work.mkdir()
        for name in ("Snakefile", "config", "workflow", "src"):
            src = new_root / name
            (shutil.copytree if src.is_dir() else shutil.copy2)(src, work / name)
        shutil.copytree(old_root / "results", work / "results")
        (work / "reports").mkdir()
        shutil.copy2(old_root / "reports/icosim_report.html", work / "reports/icosim_report.html")
        base = [snakemake, "-c1", "--directory", str(work), "--snakefile", str(work / "Snakefile"), *snakemake_args]
        subprocess.run(base + ["--touch"], check=True, capture_output=True)  # OLD's results count as up to date
        for rel in REBUILT:  # ... except what is rebuilt with NEW's code
            (work / rel).unlink()
        run = subprocess.run(base + ["--rerun-triggers", "mtime"], check=True, capture_output=True, text=True)
        ran = set(re.findall(r"rule (\w+):", run.stdout + run.stderr))
        if ran != set(RERENDERED):
            problems.append(f"rerender ran {sorted(ran)}, expected exactly {sorted(RERENDERED)}")
        for rel in ("results/report/stability.html", "results/report/convergence.html", "results/report/pendulum.html"):
            if (work / rel).read_bytes() != (old_root / rel).read_bytes():
                problems.append(f"rerendered {rel} differs from OLD's")
        wp = "results/convergence/figures/work_precision.png"
        if not np.array_equal(_pixels((work / wp).read_bytes()), _pixels((old_root / wp).read_bytes())):
            problems.append(f"rerendered {wp} differs from OLD's")
        strip = lambda t: re.sub(r'<section id="provenance">.*?</section>', "", t, flags=re.S)  # noqa: E731
        if strip((work / "reports/icosim_report.html").read_text()) != strip(
            (old_root / "reports/icosim_report.html").read_text()
        ):
            problems.append("rerendered reports/icosim_report.html differs from OLD's (provenance section aside)")
    return problems


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--rerender", action="store_true", help="rebuild the report from OLD's results with NEW's code")
    parser.add_argument("--configfile", nargs="*", default=[], help="the --configfile files of the run (--rerender)")
    parser.add_argument(
        "--allow-added",
        action="append",
        default=[],
        metavar="NAME",
        help="forgive an attribute, coordinate or config_json key of this name that only NEW has (repeatable)",
    )
    parser.add_argument("--tolerances", action="store_true", help="the speed target's tolerances instead of bitwise")
    parser.add_argument("--allow-new-files", action="store_true", help="list what NEW adds (files, claims) as added")
    args = parser.parse_args(argv)
    stats = tol.new_stats()
    kwargs = dict(tolerances=args.tolerances, allow_new_files=args.allow_new_files, stats=stats)
    problems, notes = compare(args.old, args.new, args.allow_added, **kwargs)
    if args.rerender:
        problems += rerender(args.old, args.new, ["--configfile", *args.configfile] if args.configfile else [])
    for line in tol.grouped(notes) if args.tolerances else notes:
        print("note:", line)
    for line in problems:
        print("DIFFERS:", line)
    if args.tolerances:
        print(tol.summary_table(stats))
    print(
        ("equal" + (" within the tolerances" if args.tolerances else ""))
        if not problems
        else f"{len(problems)} difference(s)"
    )
    print(
        "exceptions made: attributes "
        + ", ".join(sorted(VOLATILE_ATTRS))
        + "; variables "
        + "; ".join(f"{f}: {', '.join(sorted(v))}" for f, v in VOLATILE_VARIABLES.items())
        + "; figures "
        + ", ".join(sorted(VOLATILE_FIGURES))
        + "; report: timing phrases and columns, provenance"
        + (f"; added in NEW only: {', '.join(args.allow_added)}" if args.allow_added else "")
    )
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
