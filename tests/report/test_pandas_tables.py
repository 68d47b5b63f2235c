"""Tables now built with pandas give the same content as the hand-written code they replace.

Each test keeps the replaced implementation inline as the reference.
"""

import csv
import warnings
from collections import defaultdict

import numpy as np
import pytest
import xarray as xr

from icosim.report.convergence import work_cost_table
from icosim.report.html import table
from icosim.report.stability import KEYS, cost_table
from icosim.verdicts import write_verdicts


class FakeVerdict:
    def __init__(self, record):
        self.record = record

    def as_dict(self):
        return self.record


RECORDS = [
    {
        "id": "a",
        "source": "Sect. 3.1",
        "figures": ["9", "10"],
        "statement": 'says "tab\there"',
        "verdict": "pass",
        "reference": "pass",
        "measured": "ρ = 1.04; share 0.5",
    },
    {
        "id": "b",
        "source": "Sect. 5",
        "figures": ["21"],
        "statement": "two\nlines, comma",
        "verdict": "undecided",
        "reference": None,
        "measured": "",
    },
]


def old_tsv(records, path):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, delimiter="\t")
        w.writerow(["id", "source", "figures", "statement", "verdict", "reference", "measured"])
        for r in records:
            w.writerow(
                [
                    r["id"],
                    r["source"],
                    " ".join(r["figures"]),
                    r["statement"],
                    r["verdict"],
                    r["reference"] or "",
                    r["measured"],
                ]
            )


def test_claims_tsv_is_byte_for_byte_the_old_one(tmp_path):
    write_verdicts([FakeVerdict(r) for r in RECORDS], tmp_path / "c.json", tmp_path / "new.tsv")
    old_tsv(RECORDS, tmp_path / "old.tsv")
    assert (tmp_path / "new.tsv").read_bytes() == (tmp_path / "old.tsv").read_bytes()


def old_cost(panel_attrs, figures):
    """The hand-written per-figure sums the DataFrame replaced (panels without certification attributes count
    their multiprecision rechecks as certified)."""
    attrs_by_fig = defaultdict(list)
    for attrs in panel_attrs:
        attrs_by_fig[attrs["figure"]].append(attrs)
    out = {}
    for fig in figures:
        al = attrs_by_fig[fig]
        out[fig] = {
            "panels": len(al),
            "points": sum(a["n_points"] for a in al),
            "cert": sum(a.get("n_certified", a["n_high_precision"]) for a in al),
            "marginal": sum(a.get("n_marginal", 0) for a in al),
            "hp_axis": sum(a["n_high_precision_undamped"] for a in al),
            "audited": sum(a.get("n_audited", 0) for a in al),
            "overturned": sum(a.get("n_overturned", 0) for a in al),
            "cpu64": sum(a["cpu_seconds_float64"] for a in al),
            "cpucert": sum(a.get("cpu_seconds_certify", 0.0) + a.get("cpu_seconds_mp", 0.0) for a in al),
        }
    return out


def test_stability_cost_table_sums_as_before():
    rng = np.random.default_rng(1)
    attrs = [
        {
            "figure": fig,
            "n_points": 441,
            "n_high_precision": int(rng.integers(50)),
            "n_high_precision_undamped": int(rng.integers(5)),
            "cpu_seconds_float64": float(rng.random()),
            "cpu_seconds_mp": float(rng.random()),
            "other": "x",
        }
        for fig in ("9", "10", "9", "12")
    ]
    # a panel with certification attributes next to ones written before them
    attrs[1].update(n_certified=7, n_marginal=2, n_audited=4, n_overturned=1, cpu_seconds_certify=float(rng.random()))
    figures = ["9", "10", "11", "12"]  # 11 without panels: zeros, as before
    new = cost_table(attrs, figures)
    old = old_cost(attrs, figures)
    assert list(new.index) == figures and list(new.columns) == list(KEYS)
    for fig in figures:
        assert new.loc[fig].to_dict() == pytest.approx(old[fig], rel=1e-15)


def test_work_cost_table_rows_as_before():
    H = np.array([1e-3, 1e-2])
    wp = xr.Dataset(
        {
            "cpu_seconds_per_step": (("configuration", "H"), np.array([[1e-4, 3e-4], [np.nan, np.nan]])),
            "subsystem_integrations_per_step": ("configuration", np.array([4, 6], dtype=np.int32)),
            "coupling_solves_per_step": ("configuration", np.array([1, 3], dtype=np.int32)),
            "projections_per_step": ("configuration", np.array([0, 1], dtype=np.int32)),
        },
        coords={
            "configuration": ["ff projection k=0", "ff weighted k=2"],
            "H": H,
            "method": ("configuration", ["p", "w"]),
        },
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # median of an all-NaN row, as before
        per_step = wp["cpu_seconds_per_step"].median(dim="H", skipna=True).values
        new = work_cost_table(wp)
    old_rows = [
        [
            str(lab),
            f"{1e3 * t:.3g}" if np.isfinite(t) else "— (unstable at every H)",
            str(int(a)),
            str(int(b)),
            str(int(c)),
        ]
        for lab, t, a, b, c in zip(
            wp["configuration"].values,
            per_step,
            wp["subsystem_integrations_per_step"].values,
            wp["coupling_solves_per_step"].values,
            wp["projections_per_step"].values,
        )
    ]
    header = ["configuration", "ms per macro step", "subsystem integrations", "coupling solves", "projections"]
    assert table(new) == table(header, old_rows)
    assert old_rows[1][1] == "— (unstable at every H)"
