"""Every unit of other tools in ../shared/outside passes ``--check`` or is refused as docs/fmi.md's table says
("Units of other tools"): each row of that table is a scene here, its verdict and the check that decides it
measured on the real unit.  The units of fmus/ pass through their example scenes (tests/cli/test_cosim.py)."""

import re

import pytest
import yaml
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.problems.fmu.check import check_scene
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.scene import load_scene

pytestmark = [pytest.mark.outside, pytest.mark.fmu]

OM, OSP, REF = OUTSIDE / "omsimulator", OUTSIDE / "osp-quarter-truck", OUTSIDE / "reference-fmus"
FMUS = ROOT / "fmus"


def msd(m, c, d, sign=1):
    return {"fmu": str(FMUS / "msd"), "start": {"m": m, "c": c, "d": d, "x0": 0.0}, "position": "x",
            "velocity": "v", "acceleration": "a", "force": "lambda", "force_sign": sign}  # fmt: skip


KINEMATIC = {"fmu": str(FMUS / "msd_kinematic"), "start": {"m": 2.0, "c": 500.0, "d": 1.0, "x0": 0.0},
             "position": "x", "velocity": "v", "acceleration": "a", "acceleration_input": "a_in",
             "reaction_force": "F", "force_sign": -1}  # fmt: skip


def outputs_as_roles(fmu, output):
    """A unit without a continuous input named in the force role with one of its outputs everywhere."""
    return {"fmu": str(fmu), "position": output, "velocity": output, "acceleration": output, "force": output,
            "force_sign": 1}  # fmt: skip


def feedthrough(version):
    out = "Float64_continuous_output"
    return {"fmu": str(REF / version / "Feedthrough.fmu"), "position": out, "velocity": out, "acceleration": out,
            "force": "Float64_continuous_input", "force_sign": 1}  # fmt: skip


def statespace():
    """The Reference StateSpace as a mass-spring-damper in its first two states (tests/problems/fmu/test_unit_moves.py)."""
    a, b = [-250.0, -0.5, 0.0], [0.5, 0.5, 0.0]
    return {"fmu": str(REF / "fmus3" / "StateSpace.fmu"),
            "start": {"A": [[0.0, 1.0, 0.0], a, [0.0] * 3], "B": [[0.0] * 3, b, [0.0] * 3],
                      "C": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], a], "D": [[0.0] * 3, [0.0] * 3, b]},
            "position": "y[1]", "velocity": "y[2]", "acceleration": "y[3]", "force": "u[1]", "force_sign": 1}  # fmt: skip


ME = {"interface": "model-exchange"}
VERSIONS = ("fmus2", "fmus3")
OSP_CHASSIS = {"fmu": str(OSP / "Chassis.fmu"), "position": "position", "velocity": "velocity",
               "acceleration": "acceleration", "force": "force", "force_sign": -1}  # fmt: skip
OSP_WHEEL = {"fmu": str(OSP / "Wheel.fmu"), "position": "position", "velocity": "velocity",
             "acceleration": "acceleration"}  # fmt: skip

#: The table's first column -> (the unit under test, its partner, the decomposition (unit first), H).
ROWS = {
    "DualMassOscillator.System1 + System2": (
        {
            "fmu": str(OM / "DualMassOscillator.System1.fmu"),
            **ME,
            "position": "x1",
            "velocity": "v1",
            "acceleration": "a1",
            "force": "F",
            "force_sign": 1,
        },
        {
            "fmu": str(OM / "DualMassOscillator.System2.fmu"),
            **ME,
            "position_input": "x1",
            "velocity_input": "v1",
            "acceleration_input": "a1",
            "reaction_force": "F",
            "force_sign": 1,
        },
        "fd",
        1e-3,
    ),  # fmt: skip
    "QuarterCarModel.DisplacementForce.Wheel": (
        {
            "fmu": str(OM / "QuarterCarModel.DisplacementForce.Wheel.fmu"),
            "position_input": "z_c",
            "velocity_input": "der_z_c",
            "reaction_force": "F",
            "force_sign": 1,
        },
        msd(400.0, 0.0, 0.0),
        "df",
        1e-3,
    ),  # fmt: skip
    "QuarterCarModel.DisplacementForce.Chassis": (
        {
            "fmu": str(OM / "QuarterCarModel.DisplacementForce.Chassis.fmu"),
            "position": "z_c",
            "velocity": "der_z_c",
            "force": "F",
            "force_sign": 1,
        },
        KINEMATIC,
        "fd",
        1e-3,
    ),  # fmt: skip
    "QuarterCarModel.DisplacementDisplacement.Chassis, Wheel": (
        {
            "fmu": str(OM / "QuarterCarModel.DisplacementDisplacement.Chassis.fmu"),
            "position_input": "z_w",
            "velocity_input": "der_z_w",
            "force_sign": 1,
        },
        msd(40.0, 1.5e5, 0.0),
        "df",
        1e-3,
    ),  # fmt: skip
    "Chassis + Wheel (drive through in_vel)": (
        OSP_CHASSIS,
        {**OSP_WHEEL, "velocity_input": "in_vel", "reaction_force": "out_spring_damper_f", "force_sign": -1},
        "fd",
        1e-3,
    ),  # fmt: skip
    "Wheel (acceleration_input: in_vel)": (
        {**OSP_WHEEL, "acceleration_input": "in_vel", "reaction_force": "out_spring_damper_f", "force_sign": -1},
        msd(400.0, 0.0, 0.0),
        "df",
        1e-3,
    ),  # fmt: skip
    "Wheel (force: in_vel)": ({**OSP_WHEEL, "force": "in_vel", "force_sign": 1}, KINEMATIC, "fd", 1e-3),
    "StateSpace (FMI 3.0), H = 1e-3 s": (statespace(), msd(1.0, 1000.0, 2.0, -1), "ff", 1e-3),
    "StateSpace (FMI 3.0), H = 5e-4 s": (statespace(), msd(1.0, 1000.0, 2.0, -1), "ff", 5e-4),
    "Feedthrough (FMI 2.0)": (feedthrough("fmus2"), KINEMATIC, "fd", 1e-3),
    "Feedthrough (FMI 3.0)": (feedthrough("fmus3"), KINEMATIC, "fd", 1e-3),
    "Dahlquist (FMI 2.0, 3.0)": (
        [outputs_as_roles(REF / v / "Dahlquist.fmu", "x") for v in VERSIONS],
        KINEMATIC,
        "fd",
        1e-3,
    ),
    "VanDerPol (FMI 2.0, 3.0)": (
        [outputs_as_roles(REF / v / "VanDerPol.fmu", "x0") for v in VERSIONS],
        KINEMATIC,
        "fd",
        1e-3,
    ),
    "Roberts (FMI 3.0)": (outputs_as_roles(REF / "fmus3" / "Roberts.fmu", "y1"), KINEMATIC, "fd", 1e-3),
    "Resource, Stair (FMI 2.0, 3.0)": (
        [outputs_as_roles(REF / "fmus2" / "Resource.fmu", "y")]
        + [outputs_as_roles(REF / v / "Stair.fmu", "counter") for v in VERSIONS],
        KINEMATIC,
        "fd",
        1e-3,
    ),
    "BouncingBall (FMI 2.0, 3.0)": (
        [
            {**outputs_as_roles(REF / v / "BouncingBall.fmu", "h"), "velocity": "v", "acceleration": "v"}
            for v in VERSIONS
        ],
        KINEMATIC,
        "fd",
        1e-3,
    ),
    "BouncingBall as model exchange": (
        [
            {**outputs_as_roles(REF / v / "BouncingBall.fmu", "h"), **ME, "velocity": "v", "acceleration": "v"}
            for v in VERSIONS
        ],
        KINEMATIC,
        "fd",
        1e-3,
    ),  # fmt: skip
    "Clocks (FMI 3.0)": (outputs_as_roles(REF / "fmus3" / "Clocks.fmu", "h"), KINEMATIC, "fd", 1e-3),
}


def documented() -> dict:
    """docs/fmi.md's table of the other tools' units: first column -> (verdict, the check that decides it)."""
    text = (ROOT / "docs" / "fmi.md").read_text()
    section = text.split("## Units of other tools", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 5 and cells[0].startswith("`") and cells[0].endswith("`"):
            rows[cells[0].strip("`")] = (cells[2], cells[3].strip("`"))
    return rows


def test_the_table_has_a_row_per_case():
    assert set(documented()) == set(ROWS)


def measured(tmp_path, name):
    """(verdict, the deciding check, its text): ``pass`` with no check, ``note`` with the notes' checks, or
    ``refused`` with the first refused check (``scene``: refused when the scene is read).  A row of several units
    (the versions of one) has one verdict for all."""
    units, partner, decomposition, H = ROWS[name]
    where = tmp_path / re.sub(r"\W+", "_", name)
    found = {_measured(where / f"u{i}", u, partner, decomposition, H) for i, u in enumerate(_listed(units))}
    assert len({f[:2] for f in found}) == 1, found
    return found.pop()


def _listed(units):
    return units if isinstance(units, list) else [units]


def _measured(tmp_path, unit, partner, decomposition, H):
    tmp_path.mkdir(parents=True)
    data = {"subsystems": {"unit": unit, "partner": partner}, "t_end": 10 * H, "initial": "as-is",
            "coupling": {"method": "baumgarte", "index": 1, "mu": 1e-3, "decomposition": decomposition, "k": 1,
                         "H": H}}  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))  # the unit first: subsystem 1 of the decomposition
    try:
        report = check_scene(load_scene(path))
    except SceneError as exc:
        return "refused", "scene", str(exc)
    found = [f for u in report["units"] if u["name"] == "unit" for f in u["findings"]] + report["scene_findings"]
    refused = [f for f in found if f["verdict"] == "refused"]
    if refused:
        return "refused", refused[0]["check"], refused[0]["detail"]
    notes = [f["check"] for f in found if f["verdict"] == "note" and f["check"] not in ("units", "description")]
    return ("note", ", ".join(notes), "") if notes else ("pass", "", "")


@pytest.mark.parametrize("name", list(ROWS))
def test_each_unit_gets_the_verdict_the_table_says(tmp_path, name):
    verdict, check, detail = measured(tmp_path, name)
    assert (verdict, check or "-") == documented()[name], detail


def test_the_refusals_name_what_the_unit_is(tmp_path):
    assert "compliant unit (velocity in, force out)" in measured(tmp_path, "Wheel (acceleration_input: in_vel)")[2]
    assert re.search(r"acceleration: required", measured(tmp_path, "QuarterCarModel.DisplacementForce.Chassis")[2])
    assert (
        "reaction_force: required" in measured(tmp_path, "QuarterCarModel.DisplacementDisplacement.Chassis, Wheel")[2]
    )
    assert "event indicator" in measured(tmp_path, "BouncingBall as model exchange")[2]
    assert "scheduled execution only" in measured(tmp_path, "Clocks (FMI 3.0)")[2]
    assert "trapezoid" in measured(tmp_path, "StateSpace (FMI 3.0), H = 5e-4 s")[2]
