"""Units that nobody here wrote: typed start values and refusals on what other people's tools produce.

* pythonfmu's own example slave (``pythonfmu/tests/slaves/pythonslave.py``, shipped in its wheel), exported by
  pythonfmu: Integer, Boolean and String parameters, each set with its own setter;
* binary FMUs from the gemseo-fmu wheel (PyPI): ``Mass_Damper`` and ``MassSpringSubSystem1``, exported by
  OpenModelica 1.19/1.21 (co-simulation without saved states: refused, naming the flag), and ``FMU3Model``, an
  FMI 3.0 export of pythonfmu3 with Int32, Int64, Boolean, String and Enumeration inputs.

The gemseo-fmu wheel is fetched once from the package index into ``build/external`` (``pip download``); without
an index the tests that need it are skipped, unless ``ICOSIM_REQUIRE_EXTERNAL=1`` (CI) makes that a failure."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.problems.fmu.build import build_unit
from icosim.problems.fmu.errors import FmuError
from icosim.problems.fmu.units import Unit
from icosim.problems.fmu.variables import VariableTable

pytestmark = pytest.mark.fmu

CACHE = ROOT / "build" / "fmus"
EXTERNAL = ROOT / "build" / "external"
GEMSEO_FMU = ("gemseo-fmu", "3.1.1", "gemseo_fmu/problems/fmu_files/linux")


def external_fmu(name: str) -> Path:
    """An FMU of the gemseo-fmu wheel (downloaded once, not installed: its package is not needed)."""
    package, version, folder = GEMSEO_FMU
    target = EXTERNAL / f"{package}-{version}" / f"{name}.fmu"
    if target.is_file():
        return target
    if not sys.platform.startswith("linux"):
        pytest.skip("the gemseo-fmu wheel's binaries here are for Linux")
    wheels = EXTERNAL / "wheels"
    run = subprocess.run(
        [sys.executable, "-m", "pip", "download", "-q", "--no-deps", f"{package}=={version}", "-d", str(wheels)],
        capture_output=True,
        text=True,
    )
    found = sorted(wheels.glob(f"{package.replace('-', '_')}-{version}-*.whl"))
    if run.returncode != 0 or not found:
        message = f"{package}=={version} could not be fetched from the package index: {run.stderr.strip()[-300:]}"
        if os.environ.get("ICOSIM_REQUIRE_EXTERNAL") == "1":
            pytest.fail(message)
        pytest.skip(message)
    target.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(found[0]) as wheel:
        for member in wheel.namelist():
            if member.startswith(folder + "/") and member.endswith(".fmu"):
                part = target.parent / (Path(member).name + ".part")
                part.write_bytes(wheel.read(member))
                part.replace(target.parent / Path(member).name)
    return target


def read_back(unit, name, getter, n=None):
    var = unit.table.by_name[name]
    get = getattr(unit.fmu, getter)
    return get([var.valueReference], n) if n is not None else get([var.valueReference])


# -- pythonfmu's example --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def pythonslave():
    import pythonfmu

    return build_unit(Path(pythonfmu.__file__).parent / "tests" / "slaves" / "pythonslave.py", CACHE)


def test_pythonfmu_example_takes_typed_parameters_with_their_own_setters(pythonslave):
    start = {"intParam": 7, "booleanParameter": True, "stringParameter": "cat", "container.someReal": 1.5,
             "container.subContainer.someInteger": -3, "realIn": 0.25}  # fmt: skip
    unit = Unit("slave", pythonslave, {}, start)
    try:
        setters = {s.name: s.setter for s in unit.start_values}
        assert setters["intParam"] == "fmi2SetInteger" and setters["booleanParameter"] == "fmi2SetBoolean"
        assert setters["stringParameter"] == "fmi2SetString" and setters["realIn"] == "fmi2SetReal"
        assert read_back(unit, "intParam", "getInteger") == [7]
        assert read_back(unit, "booleanParameter", "getBoolean") == [True]
        assert read_back(unit, "stringParameter", "getString") == [b"cat"]
        assert read_back(unit, "container.someReal", "getReal") == [1.5]
        assert read_back(unit, "container.subContainer.someInteger", "getInteger") == [-3]
    finally:
        unit.close()


@pytest.mark.parametrize(
    "start, needle",
    [
        ({"intParam": 1.5}, "'intParam' is declared Integer, which takes an integer; got 1.5"),
        ({"booleanParameter": "yes"}, "'booleanParameter' is declared Boolean, which takes true or false"),
        ({"stringParameter": 3}, "'stringParameter' is declared String"),
        ({"realOut": 1.0}, "'realOut' is an output with initial = calculated"),
    ],
)
def test_pythonfmu_example_refuses_a_wrong_start(pythonslave, start, needle):
    with pytest.raises(FmuError, match=None) as info:
        Unit("slave", pythonslave, {}, start)
    assert needle in str(info.value)


# -- binary units from another package: OpenModelica and pythonfmu3 exports ---------------------------------------


@pytest.mark.parametrize("name", ["Mass_Damper", "MassSpringSubSystem1"])
def test_openmodelica_units_without_saved_states_are_refused(capsys, tmp_path, name):
    fmu = external_fmu(name)
    other = {"fmu": str(ROOT / "fmus" / "msd"), "position": "x", "velocity": "v", "acceleration": "a",
             "force": "lambda", "force_sign": -1}  # fmt: skip
    mine = {"fmu": str(fmu), "interface": "co-simulation", "position": "y", "velocity": "y", "acceleration": "y",
            "force": "f", "force_sign": 1}  # fmt: skip
    data = {"subsystems": {"om": mine, "msd": other}, "t_end": 0.01,
            "coupling": {"method": "baumgarte", "index": 3, "decomposition": "ff", "k": 0, "H": 1e-3}}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["cosim", str(path), "--check"]) == 2
    text = capsys.readouterr().out
    assert "om: " in text and "open          refused" in text and "canGetAndSetFMUstate=false" in text


def test_start_values_reach_a_pythonfmu3_binary_of_another_package(tmp_path):
    """FMU3Model (gemseo-fmu, exported by pythonfmu3 0.2.2): no saved states, so not a scene's unit; its Int32,
    Int64, Boolean, String and Float64 inputs and parameter are checked and set with their own setters as a
    scene's start values are, and read back; its Enumeration input would go to fmi3SetInt64 (the FMI 3.0 setter
    of enumerations; this unit's own setter of it fails inside pythonfmu3 0.2.2, so it is not set here)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave
    from fmpy.simulation import apply_start_values

    fmu = external_fmu("FMU3Model")
    md = read_model_description(str(fmu))
    table = VariableTable("gemseo", md, {})
    starts = table.start_values({"int32": -5, "int64": 2**40, "boolean": False, "string": "bar",
                                 "enumeration": "BLUE", "increment": 2.5})  # fmt: skip
    setters = {s.name: s.setter for s in starts}
    assert setters["enumeration"] == "fmi3SetInt64" and setters["string"] == "fmi3SetString"
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu), str(tmp_path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="gemseo")  # fmt: skip
    slave.instantiate()
    try:
        slave.enterInitializationMode()
        for s in starts:
            if s.name != "enumeration":
                apply_start_values(slave, md, {s.name: s.value})
        ref = {v.name: v.valueReference for v in md.modelVariables}
        assert slave.getInt32([ref["int32"]]) == [-5] and slave.getInt64([ref["int64"]]) == [2**40]
        assert slave.getBoolean([ref["boolean"]]) == [False] and slave.getString([ref["string"]]) == ["bar"]
        assert slave.getFloat64([ref["increment"]]) == [2.5]
        slave.exitInitializationMode()
        slave.terminate()
    finally:
        slave.freeInstance()
    for bad, needle in ((("enumeration", "PURPLE"), "items: RED (1), GREEN (2), BLUE (3)"), (("int32", True), "Int32")):
        with pytest.raises(FmuError) as info:
            table.start_values(dict([bad]))
        assert needle in str(info.value)
