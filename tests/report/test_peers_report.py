"""The peers study's report section (icosim.report.peers) on a dataset made by hand: the fastest run per error level
and icosim's time over each peer's, and where icosim does not win with the macro steps, doSteps per macro step and
time per doStep of the two runs -- every statement checked against the numbers the test chose."""

import re

from peers_data import dataset, run

from icosim.figures import save_figure
from icosim.figures.peers import peers_figure
from icosim.report.peers import fastest_rows, not_won_items, peers_section, run_rows
from icosim.studies.peers.fastest import fastest, runs

ME = {"series": "icosim, k = 2", "interface": "model exchange", "check_steps": 30.0}
ROWS = [
    run("libcosim", 1e-3, 4e-3, 0.10, 2000, 1000),
    run("libcosim", 5e-4, 2e-3, 0.20, 4000, 2000),
    run("Ecos", 1e-3, 4e-3, 0.05, 2000, 1000),
    run("FMPy", 1e-3, 0.0, 0.0, 0, 0, status="missing: fmpy (test)"),
    run("icosim", 1e-2, 5e-4, 0.30, 400, 100, **ME),
    run("icosim", 5e-3, 5e-5, 0.60, 800, 200, **ME),
]


def test_the_fastest_run_per_level_is_the_quickest_with_its_error_at_most_the_level():
    ds = dataset(ROWS)
    table = fastest(runs(ds), [1e-2, 1e-3, 1e-4, 1e-6])
    assert [e["level"] for e in table] == [1e-2, 1e-3, 1e-4]  # 1e-6: no run reaches it
    top = table[0]
    assert {m: r["wall"] for m, r in top["best"].items()} == {"libcosim": 0.10, "Ecos": 0.05, "icosim": 0.30}
    assert top["icosim_over"] == {"libcosim": 0.30 / 0.10, "Ecos": 0.30 / 0.05}
    assert list(table[1]["best"]) == ["icosim"] and table[2]["best"]["icosim"]["wall"] == 0.60
    rows = fastest_rows(ds)
    assert "libcosim 3, Ecos 6" in rows[0][2] and rows[1][2] == "no peer reaches it"


def test_where_icosim_does_not_win_the_section_gives_the_measured_cost_of_both_runs():
    items = not_won_items(dataset(ROWS))
    assert len(items) == 2  # at 1e-2 against libcosim and Ecos; alone below
    libcosim, ecos = items
    assert "libcosim" in libcosim and "3 times faster" in libcosim and "6 times faster" in ecos
    # icosim: 100 macro steps of 400 / 100 = 4 doSteps, 0.3 s / 400 = 750 µs each; libcosim: 1000 of 2, 50 µs
    assert "100 macro steps of 4 doSteps, 750 µs per doStep, and 30 probing doSteps" in libcosim
    assert "1000 macro steps of 2 doSteps, 50 µs per doStep" in libcosim
    numbers = re.search(r"needs ([\d.]+) times the peer's macro steps but ([\d.]+) times its doSteps per macro "
                        r"step, ([\d.]+) times its doSteps in all, at ([\d.]+) times its time per doStep", libcosim)  # fmt: skip
    assert [float(x) for x in numbers.groups()] == [100 / 1000, 4 / 2, 400 / 2000, 750 / 50]
    # fewer doSteps in all, each dearer: the time per doStep is the cause, the units' integration in it
    assert "each of its doSteps costs more" in libcosim and "Model Exchange units" in libcosim
    assert "outweigh" not in libcosim


def test_more_dosteps_per_macro_step_than_the_fewer_macro_steps_save_is_named_as_the_cause():
    rows = [run("Ecos", 1e-3, 4e-3, 0.05, 2000, 1000), run("icosim", 4e-3, 1e-3, 0.2, 5000, 250, series="icosim")]
    (item,) = not_won_items(dataset(rows))
    assert "its doSteps per macro step outweigh its fewer macro steps" in item
    assert "Model Exchange" not in item


def test_a_master_not_installed_is_a_row_with_its_reason_and_a_win_everywhere_is_said(tmp_path):
    ds = dataset([run("Ecos", 1e-3, 4e-3, 0.5, 2000, 1000), run("icosim", 1e-2, 5e-4, 0.3, 400, 100, **ME),
                  run("FMPy", 1e-3, 0.0, 0.0, 0, 0, status="missing: fmpy (test)")])  # fmt: skip
    assert ["FMPy", "fixed step, h = 0.001", "missing: fmpy (test)"] == run_rows(ds)[2][:3]
    png = tmp_path / "peers.png"
    save_figure(peers_figure([ds], title="peers"), png)
    html = peers_section(systems=[ds], claims=[], figure=png)
    assert "icosim is the fastest master at every error level a peer reaches" in html
    assert "missing: fmpy (test)" in html and 'id="peers"' in html
