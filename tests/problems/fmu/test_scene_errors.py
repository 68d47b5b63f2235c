"""Bad FMU scenes: exit status 2 and one line naming the file, the unit and the key, before any work; a unit
that refuses a step stops the run naming the unit, the macro step and the time, and no dataset is written."""

import zipfile

import pytest
import yaml
from helpers import ROOT

from icosim.cli import main
from icosim.problems.fmu.build import build_unit

pytestmark = pytest.mark.fmu

CACHE = ROOT / "build" / "fmus"


@pytest.fixture(autouse=True, scope="module")
def scene_schema_checker():
    """Scene files are checked with jsonschema (the fmi extra)."""
    return pytest.importorskip("jsonschema", reason="scene files are checked with jsonschema (the fmi extra)")


def body(i, **over):
    s = {
        "fmu": str(ROOT / "fmus" / "msd"),
        "start": {"m": float(i), "c": 1000.0, "d": 2.0, "x0": 0.1},
        "position": "x",
        "velocity": "v",
        "acceleration": "a",
        "force": "lambda",
        "force_sign": 1 if i == 1 else -1,
    }
    return {**s, **over}


def scene(tmp_path, body1=None, body2=None, **top):
    data = {
        "subsystems": {"body1": body1 or body(1), "body2": body2 or body(2)},
        "coupling": {"method": "baumgarte", "decomposition": "ff", "k": 1, "index": 2, "mu": 1e-3, "H": 1e-3},
        "t_end": 0.02,
    }
    for key, value in top.items():
        if key == "coupling":
            data["coupling"].update(value)
        else:
            data[key] = value
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def cosim(capsys, path, tmp_path):
    out = tmp_path / "run.nc"
    status = main(["cosim", str(path), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    return status, err, out


def edited_unit(tmp_path, edit, name="edited.fmu"):
    """The built msd unit with its modelDescription.xml passed through ``edit``."""
    src = build_unit(ROOT / "fmus" / "msd", CACHE)
    target = tmp_path / name
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                data = edit(data.decode()).encode()
            zout.writestr(item, data)
    return target


def assert_refused(status, err, out, *needles):
    assert status == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith("icosim cosim: error: ")
    for needle in needles:
        assert needle in err, err
    assert not out.exists()


def test_a_good_scene_runs(capsys, tmp_path):
    status, err, out = cosim(capsys, scene(tmp_path), tmp_path)
    assert status == 0 and out.exists(), err


def test_missing_fmu(capsys, tmp_path):
    path = scene(tmp_path, body2=body(2, fmu="nowhere.fmu"))
    assert_refused(
        *cosim(capsys, path, tmp_path), "scene.yaml", "subsystems.body2.fmu", "nowhere.fmu", "does not exist"
    )


def test_corrupt_fmu(capsys, tmp_path):
    (tmp_path / "broken.fmu").write_bytes(b"this is not a zip archive")
    path = scene(tmp_path, body1=body(1, fmu="broken.fmu"))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "broken.fmu", "not an FMU")


def test_fmu_without_model_description(capsys, tmp_path):
    with zipfile.ZipFile(tmp_path / "empty.fmu", "w") as zf:
        zf.writestr("readme.txt", "nothing")
    path = scene(tmp_path, body1=body(1, fmu="empty.fmu"))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "empty.fmu", "no readable modelDescription.xml")


def test_unit_without_saved_states(capsys, tmp_path):
    fmu = edited_unit(tmp_path, lambda xml: xml.replace('canGetAndSetFMUstate="true"', 'canGetAndSetFMUstate="false"'))
    path = scene(tmp_path, body2=body(2, fmu=fmu.name))
    assert_refused(
        *cosim(capsys, path, tmp_path), "body2", "canGetAndSetFMUstate=false", "more than once", "fmi2SetFMUstate"
    )


def test_model_exchange_only_unit(capsys, tmp_path):
    def to_me(xml):
        head, rest = xml.split("<CoSimulation", 1)
        rest = rest.split(">", 1)[1].replace("</CoSimulation>", "</ModelExchange>", 1)
        return head + '<ModelExchange modelIdentifier="msd" canGetAndSetFMUstate="true">' + rest

    fmu = edited_unit(tmp_path, to_me)
    path = scene(tmp_path, body1=body(1, fmu=fmu.name, interface="co-simulation"))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "offers model exchange only")
    # interface auto takes its model exchange, which this co-simulation binary lacks
    path = scene(tmp_path, body1=body(1, fmu=fmu.name))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "could not be instantiated", "fmi2CompletedIntegratorStep")


def test_variable_the_unit_lacks_lists_close_matches(capsys, tmp_path):
    path = scene(tmp_path, body2=body(2, force="lamda"))
    assert_refused(*cosim(capsys, path, tmp_path), "body2", "force", "'lamda'", "close matches: lambda")


def test_start_value_of_an_unknown_variable(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, start={"xo": 0.1}))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "start", "'xo'", "close matches:", "x0")


def test_variable_with_the_wrong_causality(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, force="x"))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "force", "'x'", "causality 'output'", "input")


def test_output_named_as_an_input(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, position="lambda"))
    assert_refused(*cosim(capsys, path, tmp_path), "body1", "position", "causality 'input'")


def test_refused_step_names_unit_step_and_time(capsys, tmp_path):
    b2 = body(2)
    b2["start"]["fail_time"] = 0.01
    status, err, out = cosim(capsys, scene(tmp_path, body2=b2), tmp_path)
    assert_refused(status, err, out, "unit body2", "macro step 11", "t = 0.01 s", "discard", "no dataset written")


@pytest.mark.parametrize(
    "top, needles",
    [
        ({"coupling": {"method": "newton"}}, ["coupling.method", "'newton'", "baumgarte, weighted, projection"]),
        ({"coupling": {"scheme": "seidel"}}, ["coupling.scheme", "jacobi, gauss-seidel-12"]),
        ({"coupling": {"k": -1}}, ["coupling.k"]),
        ({"coupling": {"H": 0}}, ["coupling.H"]),
        ({"coupling": {"beta": 1.0}}, ["coupling", "beta"]),
        ({"coupling": {"inputs": "spline"}}, ["coupling.inputs", "auto, derivatives, substeps"]),
        ({"coupling": {"decomposition": "dd"}}, ["not defined", "'dd'"]),
        ({"t_end": 0.0105}, ["t_end", "whole number"]),
        ({"speed": 1}, ["top level", "'speed' was unexpected"]),
        ({"t_end": "1.0e6"}, ["t_end", "write the exponent with its sign"]),
    ],
)
def test_scene_keys_are_checked_before_loading(capsys, tmp_path, top, needles):
    assert_refused(*cosim(capsys, scene(tmp_path, **top), tmp_path), "scene.yaml", *needles)


def test_unknown_subsystem_key(capsys, tmp_path):
    path = scene(tmp_path, body1=body(1, forse="lambda"))
    assert_refused(*cosim(capsys, path, tmp_path), "subsystems.body1", "'forse' was unexpected", "allowed keys")


def test_projection_needs_the_setters(capsys, tmp_path):
    path = scene(tmp_path, coupling={"method": "projection", "index": None, "mu": None})
    text = path.read_text().replace("  index: null\n", "").replace("  mu: null\n", "")
    path.write_text(text)
    assert_refused(*cosim(capsys, path, tmp_path), "subsystems.body1.mass", "projects")


def test_kinematic_subsystem_needs_its_keys(capsys, tmp_path):
    path = scene(tmp_path, coupling={"decomposition": "fd"})
    assert_refused(*cosim(capsys, path, tmp_path), "subsystems.body2.acceleration_input", "kinematic")


def test_bad_output_directory(capsys, tmp_path):
    status = main(["cosim", str(scene(tmp_path)), "--out", str(tmp_path / "no" / "run.nc")])
    err = capsys.readouterr().err.strip()
    assert status == 2 and "argument --out" in err and len(err.splitlines()) == 1


def test_missing_scene_file(capsys, tmp_path):
    status, err, out = cosim(capsys, tmp_path / "none.yaml", tmp_path)
    assert_refused(status, err, out, "none.yaml", "no such scene file")


def test_yaml_error(capsys, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text("subsystems: [unclosed\n")
    assert_refused(*cosim(capsys, path, tmp_path), "scene.yaml", "not valid YAML")
