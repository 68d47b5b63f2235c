"""The peers study's section of the report: icosim beside libcosim, Ecos and FMPy on the same unit files, work
against precision per system, each run's error, time and doSteps, per error level the fastest run of each master
with icosim's time over each peer's, where icosim does not win with what the two runs' time goes to, and the
claims.

Everything shown comes from the system datasets the workflow wrote (``results/peers/<system>.nc``,
:mod:`icosim.studies.peers.study`, read back by :mod:`icosim.studies.peers.fastest`) and the claim verdicts;
nothing is computed again here.
"""

from __future__ import annotations

import math

from ..studies.peers.fastest import cost, fastest, not_won, runs
from ..verdicts import verdict_counts
from . import html as rp
from .claims import claims_table

__all__ = ["peers_section", "run_rows", "fastest_rows", "not_won_items", "reference_text"]

esc = rp.escape
_num = rp.number


def _us(seconds) -> str:
    return _num(1e6 * seconds, ".3g") + " µs"


def _setting(r) -> str:
    """A run's setting without its master's name (the column beside says it)."""
    head = f"{r['master']}, "
    return esc(r["setting"][len(head) :] if r["setting"].startswith(head) else r["setting"])


def run_rows(ds) -> list:
    """One row per run: master, setting, status or error, wall time, timed runs, doSteps, macro steps, doSteps per
    macro step, the checks' probing doSteps."""
    rows = []
    for r in runs(ds):
        if r["status"] != "completed":
            rows.append([esc(r["master"]), _setting(r), esc(r["status"]), "—", "—", "—", "—", "—", "—"])
            continue
        c = cost(r)
        rows.append([esc(r["master"]), _setting(r), _num(r["error"]), _num(r["wall"], ".3f"),
                     _num(r["timed_runs"], ".0f"), _num(r["do_steps"], ".0f"), _num(r["macro_steps"], ".0f"),
                     _num(c["do_steps_per_macro_step"], ".3g"), _num(r["check_steps"], ".0f")])  # fmt: skip
    return rows


def _ratio(x) -> str:
    return "—" if not math.isfinite(x) else f"{x:.3g}"


def fastest_rows(ds) -> list:
    """One row per error level some run reaches: the level, each master's fastest run (setting, wall time,
    doSteps), icosim's time over each peer's."""
    table = fastest(runs(ds), ds.attrs["levels"])
    rows = []
    for e in table:
        best = "; ".join(f"<b>{esc(m)}</b>: {_setting(r)} ({r['wall']:.3f} s, {r['do_steps']:.0f} doSteps)"
                         for m, r in e["best"].items())  # fmt: skip
        ratios = ", ".join(f"{esc(m)} {_ratio(v)}" for m, v in e["icosim_over"].items())
        if "icosim" not in e["best"]:
            ratios = "icosim reaches no run"
        elif not e["icosim_over"]:
            ratios = "no peer reaches it"
        rows.append([f"{e['level']:.0e}", best, ratios])
    return rows


def _cause(q: dict, interface: str) -> str:
    """Which of icosim's cost ratios to the peer's (:func:`~icosim.studies.peers.fastest.not_won`) make it slower."""
    do_ratio = q["macro_steps"] * q["do_steps_per_macro_step"]
    parts = []
    if q["macro_steps"] >= 1:
        parts.append("icosim takes as many macro steps or more")
    elif do_ratio > 1:
        parts.append("its doSteps per macro step outweigh its fewer macro steps")
    if q["wall_per_do_step"] > 1:
        own = ", integrating the Model Exchange units included" if interface == "model exchange" else ""
        parts.append(f"each of its doSteps costs more (the master's own work per doStep{own})")
    return " and ".join(parts) or "the checks' probing doSteps and the start (no step count explains it)"


def not_won_items(ds) -> list[str]:
    """Where icosim does not win (:func:`~icosim.studies.peers.fastest.not_won`), each with the two runs' cost:
    macro steps, doSteps per macro step, time per doStep."""
    items = []
    for w in not_won(fastest(runs(ds), ds.attrs["levels"])):
        p, pc = w["peer_run"], w["peer_cost"]
        peer = (f"{esc(w['peer'])} ({_setting(p)}: {p['wall']:.3f} s, {pc['macro_steps']:.0f} macro steps of "
                f"{pc['do_steps_per_macro_step']:.3g} doSteps, {_us(pc['wall_per_do_step'])} per doStep)")  # fmt: skip
        if w["icosim"] is None:
            items.append(f"error ≤ {w['level']:.0e}: {peer} reaches it; no icosim run of the study does")
            continue
        ic, c, q = w["icosim"], w["icosim_cost"], w["cost_ratio"]
        do_ratio = q["macro_steps"] * q["do_steps_per_macro_step"]
        why = (f"icosim needs {_ratio(q['macro_steps'])} times the peer's macro steps but "
               f"{_ratio(q['do_steps_per_macro_step'])} times its doSteps per macro step, "
               f"{_ratio(do_ratio)} times its doSteps in all, at {_ratio(q['wall_per_do_step'])} times its time per "
               "doStep")  # fmt: skip
        verdict = _cause(q, ic["interface"])
        items.append(
            f"error ≤ {w['level']:.0e}: {peer} is {_ratio(w['ratio'])} times faster than icosim ({_setting(ic)}: "
            f"{ic['wall']:.3f} s, {c['macro_steps']:.0f} macro steps of {c['do_steps_per_macro_step']:.3g} doSteps, "
            f"{_us(c['wall_per_do_step'])} per doStep, and {c['check_steps']:.0f} probing doSteps of its checks). "
            f"Measured cause: {why}: {verdict}."
        )  # fmt: skip
    return items


def reference_text(ds) -> str:
    """The system's reference, from the dataset's attributes."""
    a = ds.attrs
    if a["system"] == "quarter_truck" and "reference_x" in a:
        steps = ", ".join(f"{h:g}" for h in ds["reference_step"].values)
        return (f"{esc(a['reference'])} at h = {steps} s: x({a['t_end']:g} s) = {a['reference_x']:.10f} m "
                f"(its error estimated {_num(a['reference_x_error'])} m), v = {a['reference_v']:.10f} m/s; a run "
                "that ends past the stop time is compared with the reference carried to its end")  # fmt: skip
    return esc(a["reference"])


def _system_html(ds, figure) -> str:
    a = ds.attrs
    items = not_won_items(ds)
    done = [r for r in runs(ds) if r["status"] == "completed"]
    wins = (
        "<p>icosim is the fastest master at every error level a peer reaches.</p>"
        if not items and any(r["master"] == "icosim" for r in done)
        else "<ul>" + "".join(f"<li>{i}</li>" for i in items) + "</ul>"
        if items
        else "<p>No icosim run completed.</p>"
    )
    return (
        f"<h3>{esc(a['system_title'])}, {a['t_end']:g} s</h3>"
        f"<p>Error: {esc(a['measure'])}. Reference: {reference_text(ds)}. The study's runs took "
        f"{a['cpu_seconds']:.1f} CPU-s (load average {a['load_start'][0]:.2f} at the start, {a['load_end'][0]:.2f} "
        "at the end: a ratio near 1 is within the noise of a shared machine).</p>"
        + rp.table(
            [
                "master",
                "setting",
                "error or status",
                "wall (s)",
                "timed runs",
                "doSteps",
                "macro steps",
                "doSteps / macro step",
                "check doSteps",
            ],
            run_rows(ds),
        )  # fmt: skip
        + "<h4>Who reaches each error fastest</h4>"
        + rp.table(
            ["error at most", "fastest run per master", "icosim / peer (time)"], fastest_rows(ds), raw_columns=(1,)
        )  # fmt: skip
        + "<h4>Where icosim does not win</h4>"
        + wins
    )


def peers_section(*, systems, claims, figure) -> str:
    """The section as an HTML fragment (``id="peers"``); ``systems``: the system datasets; ``figure``: the PNG."""
    n = verdict_counts(claims)
    a = systems[0].attrs if systems else {}
    versions = ", ".join(f"{k[8:]} {esc(str(v))}" for k, v in a.items() if k.startswith("version_"))
    intro = (
        "<p>icosim beside the other masters on the same unit files, each run as its users run it (the units loaded, "
        "initialised and stepped to the stop time; icosim's units checked first, their probing doSteps counted "
        f"apart): {versions}. The wall time is the minimum of up to {a.get('repeat', '—')} timed runs after a "
        f"warm-up over {a.get('warmup', math.nan):g} of the interval (fewer once {a.get('budget', math.nan):g} s "
        "are spent); doSteps are summed over the units (for a Model Exchange unit its integrations over a step). A "
        "master that is not installed or cannot run a system's files is a row with the reason. "
        f"Claims: {n['pass']} pass, {n['fail']} fail, {n['undecided']} undecided.</p>"
    )
    fig = rp.figure(
        figure,
        "Per system: the wall time (top) and the doStep calls (bottom) against the error, one line per master "
        "and setting (red icosim, blue libcosim, green Ecos, purple FMPy); the faint verticals are the table's "
        "error levels.",
        alt="work-precision against the peers",
        anchor=rp.figure_anchor("peers", figure),
    )
    body = intro + fig + "".join(_system_html(ds, figure) for ds in systems)
    body += "<h3>Claims</h3>" + claims_table(claims, part="peers")
    return rp.section("Work-precision against the peers: libcosim, Ecos and FMPy on the same units", body, "peers")
