"""The peers -- libcosim (libcosimpy), Ecos (ecospy), FMPy's ``simulate_ssp`` -- on OMSimulator's QuarterCarModel
(../shared/outside/omsimulator, both decompositions, test_quarter_car's CONNECTIONS), each master as its users run
it, with the road (road.csv: 0 m until 0.1 s, then 0.1 m) fed to the Wheel's ``z``:

* libcosim: an OspSystemStructure.xml of the two units and their connections, and a libcosim scenario file that
  overrides ``wheel.z`` with the table's value at each of its breakpoints (its scenario manager);
* Ecos: its structure API, stepped to each breakpoint and ``wheel::z`` set there (``set_real``);
* FMPy: an SSP archive whose system has an input connector ``road`` connected to ``wheel.z``, and ``simulate_ssp``'s
  ``input`` (connector -> a function of time) reading the table (the value after the time given).

The runners here are the ones benchmarks/peers_signals.py times (docs/benchmarks.md).  What the tests compare
follows from the methods: the co-simulation units integrate with OpenModelica's explicit Euler at the
communication step and every peer is a Jacobi master with held inputs, so each peer's error against the
ReferenceSystem of QuarterCarModel.mo (test_quarter_car.exact, scipy at rtol 1e-12) falls by 2 per halving, and
libcosim and Ecos, which exchange the same values with the road set at the same communication point, agree far
below that error.  FMPy's clock is summed step by step, so where it falls a rounding short of 0.1 s the road
jumps a step late (an error of first order, but not smooth in the step): its convergence is tested with the time
rounded to the step grid, and the benchmark runs it as given.  Marked ``peers`` (tests/toolchains.py).  No timing is asserted.
"""

from __future__ import annotations

import csv
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from test_quarter_car import CONNECTIONS, OM
from test_quarter_car import exact as qc_exact

from icosim.order_fit import asymptotic_order
from icosim.studies.peers.runners import fixed_step_osp, libcosim, quiet

pytestmark = pytest.mark.peers

ROAD = OM / "road.csv"
#: What is read at the end: the Chassis's position and velocity.
QC_READ = {"x": ("chassis", "z_c"), "v": ("chassis", "der_z_c")}


def qc_fmu(decomposition: str, unit: str) -> Path:
    return OM / f"QuarterCarModel.{decomposition}.{unit.title()}.fmu"


def road_table(path: Path = ROAD) -> tuple[np.ndarray, np.ndarray]:
    """road.csv's times and heights (a repeated time is a jump: the later row holds after it)."""
    with path.open() as f:
        rows = [(float(r["time"]), float(r["road"])) for r in csv.DictReader(f)]
    return np.array([t for t, _ in rows]), np.array([z for _, z in rows])


def road_after(t: float, table=None) -> float:
    """The table's value just after ``t`` (the last row at or before ``t``; linear between rows of other times)."""
    times, values = road_table() if table is None else table
    i = int(np.searchsorted(times, t, side="right")) - 1
    if i < 0:
        return float(values[0])
    if i + 1 < len(times) and times[i + 1] > times[i]:
        return float(values[i] + (values[i + 1] - values[i]) * (t - times[i]) / (times[i + 1] - times[i]))
    return float(values[i])


def road_events(t_end: float) -> list[tuple[float, float]]:
    """(time, height) where the table changes its height before ``t_end``: road.csv's is one jump, at 0.1 s."""
    times, values = road_table()
    if any(b > a and vb != va for a, b, va, vb in zip(times, times[1:], values, values[1:])):
        raise ValueError(f"{ROAD}: a ramp between rows; these runners hand the peers steps only")
    return [(float(t), float(v)) for t, v, before in zip(times[1:], values[1:], values) if v != before and t < t_end]


def _variable(ref: str) -> tuple[str, str]:
    unit, name = ref.split(".", 1)
    return unit, name


def qc_osp(folder: Path, decomposition: str, step: float, t_end: float) -> tuple[Path, Path]:
    """An OspSystemStructure.xml (fixed step) of the two units with OMSimulator's connections, and a libcosim
    scenario file overriding ``wheel.z`` at the road's breakpoints."""
    fixed_step_osp(
        folder, step, {u: qc_fmu(decomposition, u) for u in ("chassis", "wheel")}, CONNECTIONS[decomposition]
    )
    events = [{"time": t, "model": "wheel", "variable": "z", "action": "override", "value": z}
              for t, z in road_events(t_end)]  # fmt: skip
    scenario = folder / "road.json"
    scenario.write_text(json.dumps({"description": "road.csv on wheel.z", "events": events, "end": t_end}))
    return folder, scenario


def libcosim_qc(folder: Path, scenario: Path, t_end: float) -> dict:
    return libcosim(folder, t_end, QC_READ, scenario=scenario)


def ecos_qc(decomposition: str, step: float, t_end: float) -> dict:
    """Ecos stepped to each of the road's breakpoints (on the step grid), ``wheel::z`` set there."""
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    for unit in ("chassis", "wheel"):
        structure.add_model(unit, str(qc_fmu(decomposition, unit)))
    for a, y, b, u in CONNECTIONS[decomposition]:
        structure.make_real_connection(f"{a}::{y}", f"{b}::{u}")
    sim = EcosSimulation(structure=structure, step_size=step)
    try:
        sim.init()
        n_end, done = int(round(t_end / step)), 0
        for t, z in road_events(t_end):
            n = int(round(t / step))
            sim.step(n - done)
            sim.set_real("wheel::z", z)
            done = n
        sim.step(n_end - done)
        out = {"t": sim.get_time(), "do_steps": 2 * n_end}
        return out | {key: sim.get_real(f"{unit}::{name}") for key, (unit, name) in QC_READ.items()}
    finally:
        sim.terminate()
        sim.free()


def qc_ssp(path: Path, decomposition: str) -> Path:
    """An SSP 1.0 archive: the two units as resources, OMSimulator's connections, and the system's input connector
    ``road`` connected to ``wheel.z`` (OMSimulator's CSV component ``BC`` has no place in FMPy's ``simulate_ssp``,
    which instantiates FMUs only)."""
    kinds: dict = {"chassis": {}, "wheel": {"z": "input"}}
    for a, y, b, u in CONNECTIONS[decomposition]:
        kinds[a][y], kinds[b][u] = "output", "input"
    components = "".join(
        f'<ssd:Component name="{n}" type="application/x-fmu-sharedlibrary" source="resources/{n}.fmu">'
        "<ssd:Connectors>"
        + "".join(f'<ssd:Connector name="{c}" kind="{k}"><ssc:Real/></ssd:Connector>' for c, k in kinds[n].items())
        + "</ssd:Connectors></ssd:Component>"
        for n in kinds
    )
    connections = "".join(
        f'<ssd:Connection startElement="{a}" startConnector="{y}" endElement="{b}" endConnector="{u}"/>'
        for a, y, b, u in CONNECTIONS[decomposition]
    )
    ssd = (
        '<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription version="1.0" name="QuarterCarModel"'
        ' xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"'
        ' xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">'
        '<ssd:System name="default"><ssd:Connectors><ssd:Connector name="road" kind="input"><ssc:Real/>'
        f"</ssd:Connector></ssd:Connectors><ssd:Elements>{components}</ssd:Elements>"
        f'<ssd:Connections><ssd:Connection startConnector="road" endElement="wheel" endConnector="z"/>{connections}'
        "</ssd:Connections></ssd:System></ssd:SystemStructureDescription>"
    )
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        for n in kinds:
            archive.write(qc_fmu(decomposition, n), f"resources/{n}.fmu")
    return path


def fmpy_qc(ssp: Path, step: float, t_end: float, *, on_grid: bool = False) -> dict:
    """FMPy's ``simulate_ssp`` (fixed step), the road read from the table at each step's start (its time summed
    step by step, so a breakpoint may fall a rounding after it: the jump a step late); ``on_grid``: that time
    rounded to the step grid first.  The last row holds the values after the last step, stamped with that step's
    start."""
    from fmpy.ssp.simulation import simulate_ssp

    table = road_table()
    road = (lambda t: road_after(round(t / step) * step, table)) if on_grid else (lambda t: road_after(t, table))
    result = simulate_ssp(str(ssp), stop_time=t_end, step_size=step, input={"road": road})
    return {"t": float(result["time"][-1]) + step, "x": float(result["chassis.z_c"][-1]),
            "v": float(result["chassis.der_z_c"][-1]), "do_steps": 2 * len(result)}  # fmt: skip


# -- the tests --------------------------------------------------------------------------------------------------

QC_END = 1.0
QC_HS = [4e-4, 2e-4, 1e-4]


def summed_clock(step: float, n: int) -> float:
    """The time after ``n`` steps summed one by one, as FMPy's ``simulate_ssp`` loop sums it."""
    t = 0.0
    for _ in range(n):
        t += step
    return t


def test_the_road_is_one_jump_at_a_tenth_of_a_second():
    assert road_events(1.0) == [(0.1, 0.1)]
    assert road_after(0.0999) == 0.0 and road_after(0.1) == 0.1 and road_after(4.0) == 0.1
    # FMPy's summed clock: 250 steps of 4e-4 fall short of 0.1 (its jump a step late), 500 of 2e-4 do not
    assert summed_clock(4e-4, 250) < 0.1 <= summed_clock(2e-4, 500)


@pytest.mark.parametrize("decomposition", tuple(CONNECTIONS))
def test_the_peers_converge_on_the_quarter_car_at_first_order_and_libcosim_and_ecos_agree(tmp_path, decomposition):
    ssp = qc_ssp(tmp_path / "qc.ssp", decomposition)
    runs: dict = {"libcosim": [], "ecos": [], "fmpy": []}
    with quiet():
        for h in QC_HS:
            runs["libcosim"].append(libcosim_qc(*qc_osp(tmp_path / f"lc_{h:g}", decomposition, h, QC_END), QC_END))
            runs["ecos"].append(ecos_qc(decomposition, h, QC_END))
            runs["fmpy"].append(fmpy_qc(ssp, h, QC_END, on_grid=True))
    for name, rs in runs.items():
        errors = [abs(r["x"] - qc_exact(r["t"])[0]) for r in rs]
        fit = asymptotic_order(QC_HS, errors)
        assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.15, (name, errors, fit)
    for a, b in zip(runs["libcosim"], runs["ecos"]):
        error = abs(a["x"] - qc_exact(a["t"])[0])
        assert abs(a["t"] - b["t"]) < 1e-9 and abs(a["x"] - b["x"]) < 1e-6 * error, (a, b, error)
