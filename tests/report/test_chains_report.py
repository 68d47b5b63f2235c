"""The chain study's figures and report section from its datasets (a small configuration computed here): every
part drawn, the orders' table rows those of the dataset, the section's counts those of the data."""

import copy
from pathlib import Path

import matplotlib.pyplot as plt
import yaml

from icosim.claims.registry import evaluate, load_claims
from icosim.figures import save_figure
from icosim.figures.chains import chain_convergence_figure, chain_placement_figure, chain_stability_figure
from icosim.report.chains import chains_section, limit_counts, order_rows
from icosim.studies.chains.convergence import convergence_data
from icosim.studies.chains.placement import placement_data
from icosim.studies.chains.stability import stability_data

ROOT = Path(__file__).resolve().parents[2]


def test_figures_and_section_from_small_datasets(tmp_path):
    cfg = copy.deepcopy(yaml.safe_load((ROOT / "config" / "chains.yaml").read_text())["chains"])
    cfg["stability"].update(n_units=[2, 3], methods=["projection"], k=[1], scan={"min": 1e-3, "max": 1.0, "n": 8})
    cfg["convergence"].update(n_units=[2], k=[1], schemes=["jacobi"], H=[2e-3, 1.41e-3, 1e-3], t_end=0.05)
    cfg["placement"].update(methods=["projection"], k=[1], schemes=["jacobi"])
    data = {
        "stability": stability_data(cfg).to_xarray(),
        "convergence": convergence_data(cfg).to_xarray(),
        "placement": placement_data(cfg).to_xarray(),
    }
    draw = {
        "stability": chain_stability_figure,
        "convergence": chain_convergence_figure,
        "placement": chain_placement_figure,
    }
    pngs = {}
    for part, fn in draw.items():
        pngs[part] = tmp_path / f"{part}.png"
        save_figure(fn(data[part], title=part), pngs[part])
        plt.close("all")
        assert pngs[part].stat().st_size > 1000
    claims = [
        v.as_dict() for v in evaluate(load_claims(ROOT / "config" / "claims" / "chains.yaml"), list(data.values()))
    ]
    html = chains_section(**data, claims=claims, figures=pngs)
    assert html.startswith('<section id="chains">')
    assert len(order_rows(data["convergence"])) == data["convergence"]["order"].size
    counts = limit_counts(data["stability"])
    assert sum(counts.values()) == data["stability"]["status"].size
    assert all(f"{c} {s}" in html for s, c in counts.items())
