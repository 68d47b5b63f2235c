"""The peers -- libcosim (libcosimpy), Ecos (ecospy), FMPy's ``simulate_ssp`` -- on the same unit files as icosim:
OSP's quarter truck (../shared/outside/osp-quarter-truck) and OMSimulator's DualMassOscillator
(../shared/outside/omsimulator), each master as its users run it.  The runners here are the ones
benchmarks/peers.py times (docs/benchmarks.md, work-precision against the peers).

What the tests compare follows from the methods, not from numbers of the code under test:

* every peer here is a non-iterative Jacobi master with a zero-order hold of the exchanged signals, first order
  in its step.  On the quarter truck (the units' internal solver RK4 at 1e-5 s, its own error far below the
  coupling's) the difference between libcosim and icosim (k = 1) at the same step falls by 2 per halving, and
  icosim's own changes are a small part of it: the difference is libcosim's first-order error;
* the DualMassOscillator's co-simulation units integrate with explicit Euler at the communication step, so a
  peer's error against the exact solution (DualMassOscillator.mo, test_drives.exact) falls by 2 per halving;
  libcosim and Ecos exchange the same values, so they agree far below that error, and FMPy (whose connectors
  start at 0) differs from them by a first-order amount;
* icosim (System1 and System2 as Model Exchange, Baumgarte index 1, k = 2, test_drives_outside.om_scene) is far
  closer to the exact solution than a peer at the same step.

Marked ``peers`` (tests/toolchains.py): the outside units, fmpy and the peer packages (the ``peers`` extra);
Ecos also needs TBB's shared library (Debian: libtbb12).  No timing is asserted.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_drives import AMPLITUDE, exact
from test_drives_outside import BAUMGARTE, om_scene
from toolchains import OUTSIDE

from icosim.order_fit import asymptotic_order
from icosim.problems.fmu.run import run_dataset_data, run_scene

pytestmark = pytest.mark.peers

TRUCK = OUTSIDE / "osp-quarter-truck"
OM = OUTSIDE / "omsimulator"
NS = 1_000_000_000  # libcosim counts time in nanoseconds
#: OMSimulator's own test of the DualMassOscillator (tests/DualMassOscillator1.py's ``## Result``: co-simulation,
#: fixed step 1e-4): x1(10), x2(10); benchmarks/peers.py prints their errors beside the peers'.
OMSIMULATOR_CS = (0.051412690223479836, 0.031858470461315964)
#: The same as Model Exchange under CVODE (tests/DualMassOscillator2.py).
OMSIMULATOR_ME = (0.05067159474969803, 0.03142555558313003)


@contextlib.contextmanager
def quiet():
    """The file descriptors 1 and 2 on /dev/null: OSP's units print a banner per instance, libcosim logs."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


# -- the quarter truck ------------------------------------------------------------------------------------------

#: The units' settings in the file (OspSystemStructure.xml): mass, the internal solver and its step.
TRUCK_UNITS = {"chassis": {"mass": 400.0}, "wheel": {"mass": 40.0}}


def truck_osp(
    folder: Path,
    step: float,
    algorithm: str = "fixedStep",
    solver: str = "Euler",
    time_step: float = 1e-5,
    tolerance: float | None = None,
) -> Path:
    """The quarter truck's OspSystemStructure.xml as the file has it, with the base step, the algorithm
    (``fixedStep`` or ``ecco``), the units' solver and its step, and ECCO's tolerances (relative and absolute)
    replaced; the units linked beside it.  The file's ECCO configuration is kept otherwise."""  # fmt: skip
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("Chassis.fmu", "Wheel.fmu"):
        if not (folder / name).exists():
            (folder / name).symlink_to(TRUCK / name)
    xml = (TRUCK / "OspSystemStructure.xml").read_text()
    xml = re.sub(r"<BaseStepSize>[^<]*<", f"<BaseStepSize>{step!r}<", xml)
    xml = xml.replace("<Algorithm>ecco</Algorithm>", f"<Algorithm>{algorithm}</Algorithm>")
    xml = xml.replace('<String value="Euler"/>', f'<String value="{solver}"/>')
    xml = xml.replace('<Real value="1e-5"/>', f'<Real value="{time_step!r}"/>')
    if tolerance is not None:
        for tag in ("RelativeTolerance", "AbsoluteTolerance"):
            xml = re.sub(f"<{tag}>[^<]*<", f"<{tag}>{tolerance!r}<", xml)
    if algorithm == "ecco":
        xml = re.sub(r"<StepSize>[^<]*<", f"<StepSize>{step!r}<", xml)
    (folder / "OspSystemStructure.xml").write_text(xml)
    return folder


def libcosim(folder: Path, t_end: float, read: dict, expose: dict | None = None, scenario: Path | None = None) -> dict:
    """libcosim on the OspSystemStructure.xml in ``folder`` to ``t_end`` (ECCO ends at the first step past it):
    the time, the last value of each of ``read`` (key -> (unit, variable)) and the doStep calls (one per unit and
    macro step).  A time-series observer of those variables alone (libcosim's last-value observer reads every
    variable of every unit after each step), and of
    ``expose`` (unit -> variables): ECCO reads the power bonds' variables through the observed ones only.
    ``scenario``: a libcosim scenario file (timed overrides of variables) run by its scenario manager."""
    from libcosimpy._internal import libcosimc, wrap_function
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver

    step_numbers = wrap_function(lib=libcosimc(), funcname="cosim_observer_get_step_numbers", restype=ctypes.c_int,
                                 argtypes=[ctypes.POINTER(CosimObserver), ctypes.c_int, ctypes.c_int64,
                                           ctypes.c_int64, ctypes.c_int64 * 2])  # fmt: skip
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_osp_config_file(osp_path=str(folder))
    observer = CosimObserver.create_time_series(buffer_size=2)
    execution.add_observer(observer)
    if scenario is not None:
        manager = CosimManipulator.create_scenario_manager()
        execution.add_manipulator(manager)
        if not execution.load_scenario(manager, str(scenario)):
            raise RuntimeError(f"libcosim: the scenario {scenario} did not load")
    index = {u.name.decode(): u.index for u in execution.slave_infos()}
    refs = {u: {v.name.decode(): v.reference for v in execution.slave_variables(i)} for u, i in index.items()}
    observed = {(unit, name) for unit, name in read.values()}
    observed |= {(unit, name) for unit, names in (expose or {}).items() for name in names}
    for unit, name in sorted(observed):
        observer.start_time_series(index[unit], refs[unit][name], CosimVariableType.REAL)
    if not execution.simulate_until(round(t_end * NS)):
        from libcosimpy._internal import get_last_error_message

        raise RuntimeError(f"libcosim: {get_last_error_message()}")
    now = execution.status().current_time
    out = {"t": now / NS}
    for key, (unit, name) in read.items():
        steps = (ctypes.c_int64 * 2)()
        step_numbers(observer.ptr(), index[unit], 0, now, steps)
        _, numbers, values = observer.time_series_real_samples(index[unit], refs[unit][name], steps[1], 1)
        out[key] = values[0]
        out["do_steps"] = len(index) * numbers[0]
    return out


#: The quarter truck's power bond (the file's two connections), which ECCO reads.
TRUCK_BOND = {"chassis": ["velocity", "force"], "wheel": ["in_vel", "out_spring_damper_f"]}


def libcosim_truck(folder: Path, t_end: float) -> dict:
    """libcosim on an OspSystemStructure.xml of the quarter truck: the chassis's position, velocity and
    acceleration at the end."""
    read = {"x": ("chassis", "position"), "v": ("chassis", "velocity"), "a": ("chassis", "acceleration")}
    return libcosim(folder, t_end, read, TRUCK_BOND)


def ecos_truck(step: float, t_end: float, solver: str = "Euler", time_step: float = 1e-5) -> dict:
    """Ecos (fixed step, the file's connections as signals, the units' settings of the file)."""
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    structure.add_model("chassis", str(TRUCK / "Chassis.fmu"))
    structure.add_model("wheel", str(TRUCK / "Wheel.fmu"))
    structure.make_real_connection("wheel::out_spring_damper_f", "chassis::force")
    structure.make_real_connection("chassis::velocity", "wheel::in_vel")
    values = {f"{unit}::{name}": value for unit, start in TRUCK_UNITS.items() for name, value in start.items()}
    for unit in TRUCK_UNITS:
        values |= {f"{unit}::solverType": solver, f"{unit}::timeStep": time_step}
    structure.add_parameter_set("file", values)
    sim = EcosSimulation(structure=structure, step_size=step)
    try:
        sim.init(parameter_set="file")
        n = int(round(t_end / step))
        sim.step(n)
        x, v, a = (sim.get_real(f"chassis::{name}") for name in ("position", "velocity", "acceleration"))
        return {"t": sim.get_time(), "x": x, "v": v, "a": a, "do_steps": 2 * n}
    finally:
        sim.terminate()
        sim.free()


def truck_scene(
    tmp_path: Path,
    H: float,
    k: int,
    t_end: float,
    *,
    method: str = "baumgarte",
    params: dict | None = None,
    solver: str = "Euler",
    time_step: float = 1e-5,
    coupling: dict | None = None,
) -> Path:
    """icosim's joint scene of the quarter truck: the Chassis force-driven (its ``force`` acts against the physical
    force: ``force_sign`` -1 as the second unit's would), the Wheel a drive through its velocity (``velocity_input:
    in_vel``, ``reaction_force: out_spring_damper_f``), fd (docs/fmi.md, units of other tools).  The Wheel's own
    position, velocity and acceleration are its body's, not the driven point's: the scene names none of them, so
    the driven point's motion is the prescribed one.  The units' settings as in the file; Baumgarte's ``mu`` is
    ``10 H`` by default (with ``mu = 1e-3`` s it diverges at ``H = 4e-3`` s)."""  # fmt: skip
    units = {name: {**start, "solverType": solver, "timeStep": time_step} for name, start in TRUCK_UNITS.items()}
    params = {"index": 1, "mu": 10 * H} if params is None and method == "baumgarte" else (params or {})
    data = {
        "subsystems": {
            "chassis": {"fmu": str(TRUCK / "Chassis.fmu"), "start": units["chassis"], "position": "position",
                        "velocity": "velocity", "acceleration": "acceleration", "force": "force", "force_sign": -1},
            "wheel": {"fmu": str(TRUCK / "Wheel.fmu"), "start": units["wheel"], "velocity_input": "in_vel",
                      "reaction_force": "out_spring_damper_f", "force_sign": -1},
        },
        "coupling": {"method": method, "decomposition": "fd", "k": k, "H": H, **params, **(coupling or {})},
        "t_end": t_end,
    }  # fmt: skip
    path = tmp_path / f"truck_{method}_{k}_{H:g}_{solver}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def icosim_run(path: Path, body: int = 0) -> dict:
    """A scene's run as :func:`icosim.problems.fmu.run.run_scene` does it (units opened and checked): the end
    time, position and velocity of the subsystem ``body``, the recorded variables' last values (``<subsystem>.<name>``),
    its doStep calls and, apart, the checks' probing steps."""
    run = run_scene(path)
    attrs = run_dataset_data(run).attrs
    out = {"t": float(run.times[-1]), "x": float(run.states[-1, body, 0]), "v": float(run.states[-1, body, 1])}
    checks = sum(int(v) for k, v in attrs.items() if k.endswith("_checks_do_step_calls"))
    out |= {"do_steps": int(attrs["do_step_calls"]), "check_steps": checks, "status": run.status, "reason": run.reason}
    for label, (names, _, values) in run.recorded.items():
        out |= {f"{label}.{name}": float(values[-1, j]) for j, name in enumerate(names)}
    if run.steps is not None:
        out |= {"accepted": int(attrs["control_accepted_steps"]), "rejected": int(attrs["control_rejected_steps"])}
    return out


# -- OMSimulator's DualMassOscillator ---------------------------------------------------------------------------

#: OMSimulator's four signal connections (tests/DualMassOscillator1.py): (from, to) as unit.variable.
DMO_CONNECTIONS = [("system2.F", "system1.F"), ("system1.x1", "system2.x1"), ("system1.v1", "system2.v1"),
                   ("system1.a1", "system2.a1")]  # fmt: skip
DMO_UNITS = {"system1": "DualMassOscillator.System1.fmu", "system2": "DualMassOscillator.System2.fmu"}
#: What is read at the end: x1 (System1's output) and x2 (System2's local mass2.s).
DMO_READ = {"x1": ("system1", "x1"), "x2": ("system2", "mass2.s")}


def dmo_osp(folder: Path, step: float) -> Path:
    """A plain OspSystemStructure.xml (fixed step, the units' defaults: x1_start 0, x2_start 0.5) with
    OMSimulator's four connections."""
    units = {n: OM / f for n, f in DMO_UNITS.items()}
    return fixed_step_osp(folder, step, units, [(*a.split(".", 1), *b.split(".", 1)) for a, b in DMO_CONNECTIONS])


def fixed_step_osp(folder: Path, step: float, units: dict, connections) -> Path:
    """A plain OspSystemStructure.xml in ``folder`` (fixed step ``step``): ``units`` name -> FMU path,
    ``connections`` as (source unit, output, target unit, input)."""
    folder.mkdir(parents=True, exist_ok=True)
    simulators = "\n".join(f'    <Simulator name="{n}" source="{f}"/>' for n, f in units.items())
    wired = "\n".join(
        f'    <VariableConnection>\n      <Variable simulator="{a}" name="{y}"/>\n'
        f'      <Variable simulator="{b}" name="{u}"/>\n    </VariableConnection>'
        for a, y, b, u in connections
    )
    (folder / "OspSystemStructure.xml").write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<OspSystemStructure xmlns="http://opensimulationplatform.com/MSMI/OSPSystemStructure" version="0.1">\n'
        f"  <BaseStepSize>{step!r}</BaseStepSize>\n  <Algorithm>fixedStep</Algorithm>\n"
        f"  <Simulators>\n{simulators}\n  </Simulators>\n  <Connections>\n{wired}\n  </Connections>\n"
        "</OspSystemStructure>\n"
    )
    return folder


def libcosim_dmo(folder: Path, t_end: float) -> dict:
    return libcosim(folder, t_end, DMO_READ)


def dmo_ssp(path: Path) -> Path:
    """An SSP 1.0 archive of the DualMassOscillator: the two units as resources, OMSimulator's four connections,
    and System2's ``mass2.s`` as an unconnected output connector (so that FMPy reads it after each step)."""
    kinds = {"system1": {"F": "input", "x1": "output", "v1": "output", "a1": "output"},
             "system2": {"F": "output", "x1": "input", "v1": "input", "a1": "input", "mass2.s": "output"}}  # fmt: skip
    components = "".join(
        f'<ssd:Component name="{n}" type="application/x-fmu-sharedlibrary" source="resources/{f}">'
        "<ssd:Connectors>"
        + "".join(f'<ssd:Connector name="{c}" kind="{k}"><ssc:Real/></ssd:Connector>' for c, k in kinds[n].items())
        + "</ssd:Connectors></ssd:Component>"
        for n, f in DMO_UNITS.items()
    )
    connections = "".join(
        f'<ssd:Connection startElement="{a.split(".")[0]}" startConnector="{a.split(".", 1)[1]}" '
        f'endElement="{b.split(".")[0]}" endConnector="{b.split(".", 1)[1]}"/>'
        for a, b in DMO_CONNECTIONS
    )
    ssd = (
        '<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription version="1.0" name="DualMassOscillator"'
        ' xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"'
        ' xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">'
        f'<ssd:System name="default"><ssd:Elements>{components}</ssd:Elements>'
        f"<ssd:Connections>{connections}</ssd:Connections></ssd:System></ssd:SystemStructureDescription>"
    )
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        for name in DMO_UNITS.values():
            archive.write(OM / name, f"resources/{name}")
    return path


def fmpy_dmo(ssp: Path, step: float, t_end: float) -> dict:
    """FMPy's ``simulate_ssp`` (fixed step): its result's last row holds the values after the last step, stamped
    with that step's start."""
    from fmpy.ssp.simulation import simulate_ssp

    result = simulate_ssp(str(ssp), stop_time=t_end, step_size=step)
    return {"t": float(result["time"][-1]) + step, "x1": float(result["system1.x1"][-1]),
            "x2": float(result["system2.mass2.s"][-1]), "do_steps": 2 * len(result)}  # fmt: skip


def ecos_dmo(step: float, t_end: float) -> dict:
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    for name, fmu in DMO_UNITS.items():
        structure.add_model(name, str(OM / fmu))
    for a, b in DMO_CONNECTIONS:
        structure.make_real_connection(a.replace(".", "::", 1), b.replace(".", "::", 1))
    sim = EcosSimulation(structure=structure, step_size=step)
    try:
        sim.init()
        n = int(round(t_end / step))
        sim.step(n)
        out = {"t": sim.get_time(), "do_steps": 2 * n}
        return out | {key: sim.get_real(f"{unit}::{name}") for key, (unit, name) in DMO_READ.items()}
    finally:
        sim.terminate()
        sim.free()


# -- the tests --------------------------------------------------------------------------------------------------

TRUCK_HS = [4e-4, 2e-4, 1e-4]
TRUCK_END = 0.2  # the chassis rises by 8 cm from its start


@pytest.fixture(scope="module")
def truck_runs(tmp_path_factory):
    """libcosim fixed step and icosim (Baumgarte index 1, k = 1) at the same steps, the units' solver RK4 at 1e-5 s."""
    tmp = tmp_path_factory.mktemp("truck")
    lc, ic = [], []
    with quiet():
        for H in TRUCK_HS:
            lc.append(libcosim_truck(truck_osp(tmp / f"lc_{H:g}", H, solver="RK4"), TRUCK_END))
            ic.append(icosim_run(truck_scene(tmp, H, 1, TRUCK_END, solver="RK4")))
    return lc, ic


def test_libcosim_and_icosim_differ_on_the_quarter_truck_by_libcosim_first_order_error(truck_runs):
    lc, ic = truck_runs
    assert all(r["status"] == "completed" for r in ic), ic
    assert all(abs(r["t"] - TRUCK_END) < 1e-12 for r in lc + ic)
    difference = [abs(a["x"] - b["x"]) for a, b in zip(lc, ic)]
    own = [abs(a["x"] - b["x"]) for a, b in zip(ic, ic[1:])]  # icosim's changes per halving
    fit = asymptotic_order(TRUCK_HS, difference)
    assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.15, (difference, fit)
    assert own[-1] < 0.05 * difference[-1], (own, difference)  # the difference is libcosim's error


def test_ecos_and_libcosim_exchange_the_same_values_on_the_quarter_truck(tmp_path):
    """Both are Jacobi masters with the units' Euler at 1e-5 s of the file: the same steps, the same result up
    to the order in which the units' floating-point work is done."""
    with quiet():
        lc = libcosim_truck(truck_osp(tmp_path, 1e-4), 0.2)
        ec = ecos_truck(1e-4, 0.2)
    assert abs(ec["t"] - lc["t"]) < 1e-9
    assert abs(ec["x"] - lc["x"]) < 1e-9 * max(1.0, abs(lc["x"])), (ec, lc)
    assert abs(lc["x"]) > 1e-3  # it moved


def test_ecco_keeps_the_file_step_bounds_and_ends_past_the_stop_time(tmp_path):
    """The file's own ECCO configuration: at least one step per MaximumStepSize, at most one per
    MinimumStepSize, the last step ending at or past the stop time."""
    with quiet():
        r = libcosim_truck(truck_osp(tmp_path, 1e-4, algorithm="ecco"), 0.2)
    steps = r["do_steps"] // 2
    assert 0.2 <= r["t"] < 0.2 + 1e-2
    assert 0.2 / 1e-2 <= steps <= 0.2 / 1e-5 + 1, steps


DMO_END = 1.0
DMO_HS = [4e-4, 2e-4, 1e-4]


@pytest.fixture(scope="module")
def dmo_peers(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dmo")
    ssp = dmo_ssp(tmp / "DualMassOscillator.ssp")
    runs = {"libcosim": [], "ecos": [], "fmpy": []}
    with quiet():
        for h in DMO_HS:
            runs["libcosim"].append(libcosim_dmo(dmo_osp(tmp / f"lc_{h:g}", h), DMO_END))
            runs["ecos"].append(ecos_dmo(h, DMO_END))
            runs["fmpy"].append(fmpy_dmo(ssp, h, DMO_END))
    return runs


def test_the_peers_converge_on_the_dual_mass_oscillator_at_first_order(dmo_peers):
    """Each at the time its run ends: FMPy's loop (``while time < stop_time``, the time summed step by step) takes
    one step past the stop time."""
    for name, runs in dmo_peers.items():
        assert all(DMO_END - 1e-9 < r["t"] < DMO_END + 1.5 * h for r, h in zip(runs, DMO_HS)), (name, runs)
        errors = [np.max(np.abs([r["x1"], r["x2"]] - exact([r["t"]])[0, :2])) for r in runs]
        fit = asymptotic_order(DMO_HS, errors)
        assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.1, (name, errors, fit)


def test_libcosim_and_ecos_agree_far_below_their_error_and_fmpy_within_their_order(dmo_peers):
    """libcosim and Ecos set the inputs from the outputs at the start; FMPy's connectors start at 0 (System1's
    first step sees F = 0, not System2's 5 N): its difference to them is first order as well."""
    lc, ec, fm = (dmo_peers[name] for name in ("libcosim", "ecos", "fmpy"))
    for a, b in zip(lc, ec):
        error = abs(a["x1"] - exact([a["t"]])[0, 0])
        assert abs(a["t"] - b["t"]) < 1e-9 and abs(a["x1"] - b["x1"]) < 1e-6 * error, (a, b, error)
    difference = [abs(b["x1"] - exact([b["t"]])[0, 0] - (a["x1"] - exact([a["t"]])[0, 0])) for a, b in zip(lc, fm)]
    fit = asymptotic_order(DMO_HS, difference)
    assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.1, (difference, fit)


def test_icosim_is_far_closer_to_the_exact_solution_than_a_peer_at_the_same_step(tmp_path, dmo_peers):
    """Baumgarte index 1, k = 2, H = 1e-3 on the Model Exchange units: x1 within a thousandth of libcosim's error
    at the finer step 4e-4."""
    with quiet():
        ic = icosim_run(om_scene(tmp_path, "baumgarte", 2, 1e-3, DMO_END, BAUMGARTE))
    x1 = exact([DMO_END])[0, 0]
    peer = abs(dmo_peers["libcosim"][0]["x1"] - x1)  # at 4e-4, a finer step than icosim's
    assert ic["status"] == "completed"
    assert abs(ic["x"] - x1) < 1e-3 * peer, (ic, peer)
    assert abs(ic["x"] - x1) < 1e-6 * AMPLITUDE
