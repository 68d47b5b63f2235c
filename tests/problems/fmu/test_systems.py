"""System files other tools wrote, read and run (icosim.problems.fmu.systems).

* OMSimulator's own SSDs (tests/data/omsimulator_ssp, from its testsuite, README there): what is read against the
  files' text and against what OMSimulator's tests print for them (``LinearTransformation1.py``: ``Add1.u1`` is 3.0
  with ``Gain1.y`` at 0 through the connection's factor 2, offset 3; ``LinearTransformation3.py``: the mapped
  parameters ``Gain1.k`` = 13.0 and ``Gain1.u`` = 14.0); a nested system and a signal connection refused by name;
* OSP's quarter truck (libcosim's ``OspSystemStructure.xml``, ../shared/outside): read as libcosim reads it, run
  as a joint (the chassis force driven, the wheel a drive through its velocity) and the same as the YAML joint
  scene with that mapping, and its chassis position against libcosim's fixed-step run of the same units.
"""

import json

import numpy as np
import pytest
import yaml
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.run import run_dataset_data, run_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.systems import read_system
from icosim.problems.fmu.systems.scene import default_coupling

OMS = ROOT / "tests" / "data" / "omsimulator_ssp"
LIBCOSIM = ROOT / "tests" / "data" / "libcosim_osp"
OSP = OUTSIDE / "osp-quarter-truck"


# -- OMSimulator's SSDs ----------------------------------------------------------------------------------------------


def test_a_connection_with_a_linear_transformation_is_read_as_omsimulator_reads_it():
    system = read_system(OMS / "LinearTransformation" / "SystemStructure.ssd")
    assert system.format == "SSP 2.0" and system.name == "default"
    assert set(system.components) == {"Add1", "Gain1"}
    assert system.components["Add1"].source == OMS / "LinearTransformation" / "resources" / "Add.fmu"
    gain = system.components["Gain1"]
    assert [(c.name, c.kind, c.type) for c in gain.connectors] == [
        ("u", "input", "Real"), ("y", "output", "Real"), ("k", "parameter", "Real")]  # fmt: skip
    assert gain.connector("k").unit == "1" and "1" in system.units
    (connection,) = system.connections
    assert connection.label == "Gain1.y -> Add1.u1"
    assert (connection.factor, connection.offset) == (2.0, 3.0)
    assert connection.apply(0.0) == 3.0  # OMSimulator: Gain1.y 0.0, Add1.u1 3.0
    assert (system.start_time, system.stop_time) == (0.0, 1.0)


def test_parameters_bound_through_a_mapping_with_transformations_get_omsimulator_s_values():
    system = read_system(OMS / "LinearTransformation3" / "SystemStructure.ssd")
    assert system.components["Gain1"].start == {"u": 14.0, "k": 13.0}  # 2 * 2 + 10, 4 * 2 + 5
    assert system.components["Add1"].start == {}
    (connection,) = system.connections
    assert (connection.factor, connection.offset) == (1.0, 0.0)


def test_an_ssp_archive_is_read_as_the_folder_it_packs(tmp_path, monkeypatch):
    """OMSimulator's suite packs each of these folders into an ``.ssp`` (its resources/CMakeLists.txt): so here."""
    import zipfile

    monkeypatch.setenv("ICOSIM_FMU_CACHE", str(tmp_path / "cache"))
    folder = OMS / "LinearTransformation3"
    archive = tmp_path / "LinearTransformation3.ssp"
    with zipfile.ZipFile(archive, "w") as z:
        for f in sorted(folder.rglob("*")):
            z.write(f, f.relative_to(folder).as_posix())
    system = read_system(archive)
    assert system.path == archive and system.format == "SSP 2.0"
    assert system.components["Gain1"].start == {"u": 14.0, "k": 13.0}
    unpacked = system.components["Gain1"].source.parent.parent
    assert unpacked.parent == tmp_path / "cache" / "ssp" and (unpacked / "SystemStructure.ssd").exists()


def test_a_nested_system_is_refused_naming_it_and_the_file():
    path = OMS / "importParameterMapping" / "SystemStructure.ssd"
    with pytest.raises(SceneError, match=r"SystemStructure\.ssd: System System2: nested systems are not supported"):
        read_system(path)


def test_an_invalid_system_structure_is_refused_naming_what_its_schema_does_not_allow():
    """OMSimulator's ``invalidSSD.py``: line 16, a Connector's "attribute 'type': The attribute 'type' is not
    allowed"."""
    with pytest.raises(SceneError) as refused:
        read_system(OMS / "invalidSSD" / "SystemStructure.ssd")
    text = str(refused.value)
    assert "invalidSSD/SystemStructure.ssd: schema: not a valid SSP 1.0 system structure" in text
    assert "'type' attribute not allowed" in text and "'name': 'C1'" in text


def test_an_invalid_parameter_file_is_refused_naming_it_as_omsimulator_does():
    """OMSimulator's ``invalidSSV.py``: System1.ssv, line 4: "The attribute 'type' is not allowed"."""
    with pytest.raises(SceneError) as refused:
        read_system(OMS / "invalidSSV" / "SystemStructure.ssd")
    text = str(refused.value)
    assert "parameter set: System1.ssv is not a valid SSP parameter set" in text
    assert "'type' attribute not allowed" in text


def test_a_system_of_signal_connections_is_a_signal_scene_with_its_transformations(tmp_path):
    """OMSimulator's LinearTransformation (``y -> u1`` with factor 2, offset 3) read before any unit is opened (its
    FMUs are not here): without a step size in the file the scene must give the coupling, and it may."""
    path = OMS / "LinearTransformation" / "SystemStructure.ssd"
    with pytest.raises(SceneError, match="SSP 2.0 gives no step size: a scene naming the system needs coupling"):
        load_scene(path)
    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump({"system": str(path), "coupling": {"H": 0.1}, "t_end": 1.0}))
    loaded = load_scene(scene)
    assert ("Gain1", "y", "Add1", "u1", 2.0, 3.0) in loaded.connections
    assert loaded.coupling["k"] == 0 and loaded.scheme.name == "jacobi" and loaded.n_steps == 10


def test_a_scene_naming_a_missing_system_is_refused_naming_its_key(tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text("system: nowhere/OspSystemStructure.xml\n")
    with pytest.raises(SceneError, match=r"scene\.yaml: system: nowhere/OspSystemStructure\.xml does not exist"):
        load_scene(scene)


def test_a_scene_naming_a_system_refuses_a_component_the_system_lacks(tmp_path):
    scene = tmp_path / "scene.yaml"
    system = OMS / "LinearTransformation3" / "SystemStructure.ssd"
    scene.write_text(yaml.safe_dump({"system": str(system), "subsystems": {"Gain2": {"interface": "auto"}}}))
    with pytest.raises(SceneError, match=r"scene\.yaml: subsystems\.Gain2: the system has no component 'Gain2'"):
        load_scene(scene)


# -- libcosim's own OSP files -----------------------------------------------------------------------------------------


def test_libcosim_s_function_blocks_are_refused_naming_the_element():
    path = LIBCOSIM / "OspSystemStructure_EndTime.xml"
    with pytest.raises(SceneError, match=r"OspSystemStructure_EndTime\.xml: Functions: libcosim's function blocks"):
        read_system(path)


def test_a_simulator_s_own_step_size_is_refused_naming_it():
    path = LIBCOSIM / "OspSystemStructure_Bond.xml"
    with pytest.raises(SceneError, match=r"_Bond\.xml: Simulator CraneController\.stepSize: a unit's own step size"):
        load_scene(path)


# -- OSP's quarter truck ----------------------------------------------------------------------------------------------


@pytest.mark.outside
def test_the_quarter_truck_is_read_as_libcosim_reads_it():
    system = read_system(OSP)  # the folder
    assert system.format == "OSP" and system.path == OSP / "OspSystemStructure.xml"
    assert system.step_size == 1e-4 and system.algorithm == "ecco" and system.start_time == 0.0
    assert system.stop_time is None
    assert system.components["chassis"].start == {"mass": 400.0, "solverType": "Euler", "timeStep": 1e-5}
    assert system.components["wheel"].start == {"mass": 40.0, "solverType": "Euler", "timeStep": 1e-5}
    assert system.components["chassis"].source == (OSP / "Chassis.fmu").resolve()
    # directions from the units' model descriptions, as libcosim connects them (the file labels the chassis's
    # velocity "input": in a power bond the causality attributes only label the bond's ends)
    assert [c.label for c in system.connections] == ["chassis.velocity -> wheel.in_vel",
                                                     "wheel.out_spring_damper_f -> chassis.force"]  # fmt: skip
    assert set(system.power_bonds()) == {"wheelchassis"}
    assert system.ecco == {"SafetyFactor": 0.99, "StepSize": 1e-4, "MinimumStepSize": 1e-5, "MaximumStepSize": 0.01,
                           "MinimumChangeRate": 0.2, "MaximumChangeRate": 1.5, "ProportionalGain": 0.2,
                           "IntegralGain": 0.15, "RelativeTolerance": 1e-6, "AbsoluteTolerance": 1e-6}  # fmt: skip


@pytest.mark.outside
def test_the_quarter_truck_s_power_bond_is_a_joint_with_the_wheel_a_velocity_drive():
    scene = load_scene(OSP / "OspSystemStructure.xml")
    subs = scene.data["subsystems"]
    assert {k: subs["chassis"][k] for k in ("force", "velocity", "position", "acceleration", "force_sign")} == {
        "force": "force", "velocity": "velocity", "position": "position", "acceleration": "acceleration",
        "force_sign": 1}  # fmt: skip
    assert {k: subs["wheel"][k] for k in ("velocity_input", "reaction_force", "force_sign")} == {
        "velocity_input": "in_vel", "reaction_force": "out_spring_damper_f", "force_sign": -1}  # fmt: skip
    assert scene.data["joints"] == [{"between": ["chassis", "wheel"], "decomposition": "fd"}]
    assert scene.data["coupling"]["H"] == 1e-4 and scene.data["t_end"] == 1.0


@pytest.mark.outside
def test_declared_units_decide_the_sides_of_a_power_bond_before_names(tmp_path):
    """The quarter truck with its Wheel's ``out_spring_damper_f`` declared in m/s (the unit edited, libcosim's file
    unchanged): the bond's velocity then runs from the wheel, which is taken as the force side."""
    import zipfile

    (tmp_path / "OspSystemStructure.xml").write_bytes((OSP / "OspSystemStructure.xml").read_bytes())
    (tmp_path / "Chassis.fmu").symlink_to(OSP / "Chassis.fmu")
    with zipfile.ZipFile(OSP / "Wheel.fmu") as zin, zipfile.ZipFile(tmp_path / "Wheel.fmu", "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                old = 'name="out_spring_damper_f" valueReference="15" variability="discrete" causality="output">\n'
                assert old + "\t\t\t<Real/>" in data.decode()
                data = data.decode().replace(old + "\t\t\t<Real/>", old + '\t\t\t<Real unit="m/s"/>', 1).encode()
            zout.writestr(item, data)
    data = yaml.safe_load(yaml.safe_dump(load_scene(tmp_path).data))
    assert data["joints"] == [{"between": ["wheel", "chassis"], "decomposition": "fd"}]
    assert data["subsystems"]["wheel"]["velocity"] == "out_spring_damper_f"
    assert data["subsystems"]["chassis"]["velocity_input"] == "force"


def _overlay(tmp_path, name, **keys):
    path = tmp_path / name
    path.write_text(yaml.safe_dump({"system": str(OSP / "OspSystemStructure.xml"), **keys}))
    return path


def _joint_scene(tmp_path, H, t_end):
    """The quarter truck as a YAML joint scene written by hand: the chassis force driven, the wheel a drive through
    its velocity (tests/problems/fmu/test_outside_units.py's row, the wheel without its body's outputs: the driven
    point is the top of its spring, whose velocity ``in_vel`` is), the start values of the OSP file."""
    chassis = {"fmu": str(OSP / "Chassis.fmu"), "start": {"mass": 400.0, "solverType": "Euler", "timeStep": 1e-5},
               "position": "position", "velocity": "velocity", "acceleration": "acceleration", "force": "force",
               "force_sign": -1}  # fmt: skip
    wheel = {"fmu": str(OSP / "Wheel.fmu"), "start": {"mass": 40.0, "solverType": "Euler", "timeStep": 1e-5},
             "velocity_input": "in_vel", "reaction_force": "out_spring_damper_f", "force_sign": -1}  # fmt: skip
    data = {"subsystems": {"chassis": chassis, "wheel": wheel},
            "coupling": {"method": "baumgarte", "index": 1, "mu": H, "decomposition": "fd", "k": 1,
                         "scheme": "jacobi", "H": H}, "t_end": t_end}  # fmt: skip
    path = tmp_path / "joint.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.outside
def test_the_quarter_truck_from_its_osp_file_runs_as_its_yaml_joint_scene(tmp_path):
    # the scene's coupling (the systems' default at the base step) replaces the file's ECCO control
    run = run_scene(_overlay(tmp_path, "osp.yaml", t_end=0.05, coupling=default_coupling(1e-4)))
    same = run_scene(_joint_scene(tmp_path, 1e-4, 0.05))
    assert run.status == same.status == "completed" and len(run.times) == 501
    scale = np.max(np.abs(same.positions[:, 0, 0]))
    assert scale > 1e-3  # the chassis moves
    np.testing.assert_allclose(run.positions, same.positions, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(run.states, same.states, rtol=0, atol=1e-10 * np.max(np.abs(same.states)))
    data = run_dataset_data(run)
    # the chassis's connectors as it holds them: its velocity output is the velocity row; its force input is the
    # joint's multiplier (force_sign +1)
    np.testing.assert_array_equal(data.array("chassis.velocity"), run.states[:, 0, 1])
    force, joint = data.array("chassis.force"), data.array("joint_force")
    np.testing.assert_allclose(force[1:], np.ravel(joint)[1:], rtol=1e-12)
    # the wheel's: a drive stood at each communication point, its velocity input the driven point's velocity, and
    # its force output the chassis's force input, as the bond says, where the corrector has balanced them
    np.testing.assert_array_equal(data.array("wheel.in_vel"), run.states[:, 1, 1])
    spring = data.array("wheel.out_spring_damper_f")
    np.testing.assert_allclose(spring[1:], force[1:], rtol=1e-9, atol=1e-9 * np.max(np.abs(force)))
    system = json.loads(data.attrs["system_json"])
    assert system["format"] == "OSP" and system["algorithm"] == "ecco" and system["ecco"]["SafetyFactor"] == 0.99


@pytest.mark.outside
def test_a_scene_naming_the_system_may_give_the_roles_itself(tmp_path):
    """The roles of the hand-written joint scene given in a scene naming the OSP file (relative to it), the
    coupling with its decomposition: the same run."""
    hand = yaml.safe_load(_joint_scene(tmp_path, 1e-4, 0.02).read_text())
    roles = {
        name: {k: v for k, v in sub.items() if k not in ("fmu", "start")} for name, sub in hand["subsystems"].items()
    }
    (tmp_path / "sys").mkdir()
    (tmp_path / "sys" / "OspSystemStructure.xml").symlink_to(OSP / "OspSystemStructure.xml")
    for unit in ("Chassis.fmu", "Wheel.fmu"):
        (tmp_path / "sys" / unit).symlink_to(OSP / unit)
    path = tmp_path / "given.yaml"
    path.write_text(yaml.safe_dump({"system": "sys", "subsystems": roles, "coupling": hand["coupling"], "t_end": 0.02}))
    scene = load_scene(path)
    assert "joints" not in scene.data and scene.data["subsystems"]["wheel"]["force_sign"] == -1
    np.testing.assert_array_equal(run_scene(scene).states, run_scene(_joint_scene(tmp_path, 1e-4, 0.02)).states)


def _libcosim(tmp_path, H, t_end):
    """libcosim's fixed-step run of the quarter truck (the OSP file with ``Algorithm`` fixedStep and the base step
    ``H``, the units linked beside it): the chassis's position at every step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    where = tmp_path / f"libcosim_{H:g}"
    where.mkdir()
    for unit in ("Chassis.fmu", "Wheel.fmu"):
        (where / unit).symlink_to(OSP / unit)
    xml = (OSP / "OspSystemStructure.xml").read_text()
    assert "<Algorithm>ecco</Algorithm>" in xml and "<BaseStepSize>0.0001</BaseStepSize>" in xml
    xml = xml.replace("<Algorithm>ecco</Algorithm>", "<Algorithm>fixedStep</Algorithm>")
    (where / "OspSystemStructure.xml").write_text(xml.replace("0.0001</BaseStepSize>", f"{H!r}</BaseStepSize>"))
    execution = CosimExecution.from_osp_config_file(osp_path=str(where))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    chassis = next(s.index for s in execution.slave_infos() if s.name.decode() == "chassis")
    ref = next(v.reference for v in execution.slave_variables(slave_index=chassis) if v.name.decode() == "position")
    x = []
    for n in range(int(round(t_end / H)) + 1):
        if n:
            execution.step()
        x.append(observer.last_real_values(slave_index=chassis, variable_references=[ref])[0])
    return np.array(x)


@pytest.mark.outside
def test_the_quarter_truck_s_chassis_follows_libcosim_within_the_two_masters_coupling_errors(tmp_path):
    """libcosim's fixed step holds each input over the step (explicit Jacobi, first order in H); icosim's Baumgarte
    at k = 1, here with one sub-step per macro step (``substeps: 1``: the input held at its polynomial's midpoint),
    is of order one at least.  So both masters step each unit over whole macro steps, and the units' own Euler runs
    at its 1e-5 s in both (H and H/2 are multiples of it): what differs is the coupling.  Each master's coupling
    error at H is then at most twice the change of its run from H to H/2 (Richardson, order >= 1), and the two
    runs may differ by the sum of the two."""
    pytest.importorskip("libcosimpy")
    H, t_end = 1e-4, 0.1
    theirs = {h: _libcosim(tmp_path, h, t_end) for h in (H, H / 2)}
    ours = {}
    for h in (H, H / 2):
        coupling = {"method": "baumgarte", "index": 1, "mu": h, "k": 1, "scheme": "jacobi", "H": h, "substeps": 1}
        ours[h] = run_scene(_overlay(tmp_path, f"osp_{h:g}.yaml", t_end=t_end, coupling=coupling)).positions[:, 0, 0]
    change = {name: np.max(np.abs(r[H] - r[H / 2][::2])) for name, r in (("libcosim", theirs), ("icosim", ours))}
    bound = 2 * (change["libcosim"] + change["icosim"])
    difference = np.max(np.abs(ours[H] - theirs[H]))
    assert np.max(np.abs(theirs[H])) > 0.03  # the chassis moves 3 cm
    assert difference <= bound, (difference, change)
    assert change["libcosim"] > 3 * change["icosim"]  # the held inputs' error dominates
