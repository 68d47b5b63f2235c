"""The signal study's figure and report section from case datasets (their numbers those of theory: errors
C H^(k+1), growth by the predicted rho): every case drawn and tabled, the growth rows those of the datasets, what
the data cannot decide listed from the datasets' own attributes."""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from icosim.claims.registry import evaluate, load_claims
from icosim.figures import save_figure
from icosim.figures.signals import signals_figure
from icosim.report.signals import case_rows, growth_rows, signals_section
from icosim.studies.signals.study import case_dataset

ROOT = Path(__file__).resolve().parents[2]
FIT = {"decades": 1.0, "tolerance": 0.1, "min_points": 3}


def dataset(by, k, H, growth=()):
    spec = {"by": by, "k": k, "H": H, "growth_H": [g[0] for g in growth]}
    spec |= {"scheme": "jacobi"} if by == "connections" else {"method": "baumgarte", "params": {"index": 1, "mu": 1e-3}}
    n = len(H)
    runs = {"error": [h ** (k + 1) for h in H], "error_end": [h ** (k + 1) for h in H],
            "predicted_rho": [0.999] * n if by == "connections" else [np.nan] * n, "rho_error": [1e-14] * n,
            "predicted_verdict": ["stable" if by == "connections" else "undecided"] * n}  # fmt: skip
    g = {"growth_rho": [r for _, r, _ in growth], "growth_rho_error": [1e-14] * len(growth),
         "growth_verdict": ["unstable" if r > 1 else "stable" for _, r, _ in growth],
         "measured_growth": [m for _, _, m in growth]}  # fmt: skip
    reason = "" if by == "connections" else "the joint's spectral radius is not predicted here"
    info = {"scheme": "jacobi", "amplitude": 0.5, "prediction_reason": reason, "predicted_H_max": 0.04}
    return case_dataset(spec, runs, g, info, fit=FIT, t_end=0.25, growth_steps=300).to_xarray()


def test_figure_and_section_from_case_datasets(tmp_path):
    H = [6.25e-4, 1.25e-3, 2.5e-3, 5e-3]
    cases = [dataset("connections", k, H, [(0.2, 1.09, 1.0905)]) for k in (0, 1)]
    cases.append(dataset("joint", 1, [3.125e-4, 6.25e-4, 1.25e-3]))
    fig = signals_figure(cases, title="t")
    err, growth = fig.axes
    assert len(err.get_lines()) == 3 and len(fig.legends[0].get_texts()) == 3
    assert sum(len(line.get_xdata()) for line in growth.get_lines() if line.get_marker() == "o") == 2
    png = tmp_path / "signals.png"
    save_figure(fig, png)
    plt.close("all")
    claims = [v.as_dict() for v in evaluate(load_claims(ROOT / "config" / "claims" / "signals.yaml"), cases)]
    html = signals_section(cases=cases, claims=claims, figure=png)
    assert html.startswith('<section id="signals">') and "data:image/png;base64," in html
    rows = case_rows(cases)
    assert [r[0] for r in rows] == ["<b>connections_jacobi_k0</b>", "<b>connections_jacobi_k1</b>",
                                    "<b>joint_baumgarte_fd_k1</b>"]  # fmt: skip
    assert "2.000 (asymptotic)" in rows[1][6] and rows[2][7].startswith("undecided: the joint")
    assert [r[2:4] for r in growth_rows(cases)] == [["1.090000 (unstable)", "1.090500"]] * 2
    assert "implicit coupling of the connections: no implicit case is configured" in html
    assert "the joint's stability: the joint&#x27;s spectral radius is not predicted" in html
