"""Each master's run of the peers' unit files, as its users run it: OSP's quarter truck (``Chassis.fmu``,
``Wheel.fmu`` and libcosim's ``OspSystemStructure.xml`` in ``unit_dir``) and OMSimulator's DualMassOscillator
(``DualMassOscillator.System1.fmu`` and ``.System2.fmu`` in ``unit_dir``).  A runner returns the end time, the
values read there and its doStep calls (one per unit and macro step; for a Model Exchange unit its integrations
over a step).

* libcosim (libcosimpy): an OspSystemStructure.xml, fixed step or ECCO, a time-series observer of the variables
  read only (its last-value observer reads every variable of every unit after each step);
* Ecos (ecospy): its structure API, fixed step, the connections as signals;
* FMPy: ``simulate_ssp`` on an SSP archive, fixed step;
* icosim: the joint scene of the quarter truck, or any scene file, run as ``run_scene`` runs it (the units
  opened and checked; the checks' probing steps counted apart).

The peer packages are imported inside the runners: a master not installed fails its runner alone.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import sys
import zipfile
from pathlib import Path

import yaml

from ...problems.fmu.run import run_dataset_data, run_scene

__all__ = [
    "quiet", "truck_osp", "libcosim", "libcosim_truck", "ecos_truck", "truck_scene", "icosim_run", "dmo_osp",
    "fixed_step_osp", "libcosim_dmo", "dmo_scene", "dmo_ssp", "fmpy_dmo", "ecos_dmo", "TRUCK_UNITS", "TRUCK_BOND",
    "DMO_CONNECTIONS", "DMO_UNITS", "DMO_READ",
]  # fmt: skip

NS = 1_000_000_000  # libcosim counts time in nanoseconds


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
#: The quarter truck's power bond (the file's two connections), which ECCO reads.
TRUCK_BOND = {"chassis": ["velocity", "force"], "wheel": ["in_vel", "out_spring_damper_f"]}


def truck_osp(
    folder: Path,
    step: float,
    *,
    unit_dir: Path,
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
            (folder / name).symlink_to(Path(unit_dir) / name)
    xml = (Path(unit_dir) / "OspSystemStructure.xml").read_text()
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


def libcosim_truck(folder: Path, t_end: float) -> dict:
    """libcosim on an OspSystemStructure.xml of the quarter truck: the chassis's position, velocity and
    acceleration at the end."""
    read = {"x": ("chassis", "position"), "v": ("chassis", "velocity"), "a": ("chassis", "acceleration")}
    return libcosim(folder, t_end, read, TRUCK_BOND)


def ecos_truck(step: float, t_end: float, *, unit_dir: Path, solver: str = "Euler", time_step: float = 1e-5) -> dict:
    """Ecos (fixed step, the file's connections as signals, the units' settings of the file)."""
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    structure.add_model("chassis", str(Path(unit_dir) / "Chassis.fmu"))
    structure.add_model("wheel", str(Path(unit_dir) / "Wheel.fmu"))
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
    unit_dir: Path,
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
    unit_dir = Path(unit_dir)
    data = {
        "subsystems": {
            "chassis": {"fmu": str(unit_dir / "Chassis.fmu"), "start": units["chassis"], "position": "position",
                        "velocity": "velocity", "acceleration": "acceleration", "force": "force", "force_sign": -1},
            "wheel": {"fmu": str(unit_dir / "Wheel.fmu"), "start": units["wheel"], "velocity_input": "in_vel",
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
    out["macro_steps"] = len(run.times) - 1
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


def dmo_scene(
    tmp_path: Path,
    method: str,
    k: int,
    H: float,
    t_end: float,
    params: dict,
    *,
    unit_dir: Path,
    tolerance: float | None = None,
    record: tuple = (),
    coupling: dict | None = None,
) -> Path:
    """icosim's joint scene of the DualMassOscillator: System1 and System2 as Model Exchange (the integrator's
    ``tolerance`` where given), fd, System1 force-driven by ``F``, System2 a drive through x1, v1, a1 (its ``F``
    the force on mass 1: ``force_sign`` 1); System2's variables ``record`` recorded; ``coupling`` keys over the
    method's."""
    me = {"interface": "model-exchange", **({} if tolerance is None else {"tolerance": tolerance})}
    unit_dir = Path(unit_dir)
    data = {
        "subsystems": {
            "system1": {"fmu": str(unit_dir / DMO_UNITS["system1"]), **me, "position": "x1", "velocity": "v1",
                        "acceleration": "a1", "force": "F", "force_sign": 1},
            "system2": {"fmu": str(unit_dir / DMO_UNITS["system2"]), **me, "position_input": "x1",
                        "velocity_input": "v1", "acceleration_input": "a1", "reaction_force": "F", "force_sign": 1,
                        **({"record": list(record)} if record else {})},
        },
        "coupling": {"method": method, "decomposition": "fd", "k": k, "H": H, "perturbation": 1.0, **params,
                     **(coupling or {})},
        "t_end": t_end,
    }  # fmt: skip
    path = tmp_path / f"dual_mass_{method}_{k}_{H:g}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def dmo_osp(folder: Path, step: float, *, unit_dir: Path) -> Path:
    """A plain OspSystemStructure.xml (fixed step, the units' defaults: x1_start 0, x2_start 0.5) with
    OMSimulator's four connections."""
    units = {n: Path(unit_dir) / f for n, f in DMO_UNITS.items()}
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


def dmo_ssp(path: Path, *, unit_dir: Path) -> Path:
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
            archive.write(Path(unit_dir) / name, f"resources/{name}")
    return path


def fmpy_dmo(ssp: Path, step: float, t_end: float) -> dict:
    """FMPy's ``simulate_ssp`` (fixed step): its result's last row holds the values after the last step, stamped
    with that step's start."""
    from fmpy.ssp.simulation import simulate_ssp

    result = simulate_ssp(str(ssp), stop_time=t_end, step_size=step)
    return {"t": float(result["time"][-1]) + step, "x1": float(result["system1.x1"][-1]),
            "x2": float(result["system2.mass2.s"][-1]), "do_steps": 2 * len(result)}  # fmt: skip


def ecos_dmo(step: float, t_end: float, *, unit_dir: Path) -> dict:
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    for name, fmu in DMO_UNITS.items():
        structure.add_model(name, str(Path(unit_dir) / fmu))
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
