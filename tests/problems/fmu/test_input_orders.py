"""Orders of input derivatives a Co-Simulation unit refuses (icosim.problems.fmu.input_orders), on OMSimulator's
DualMassOscillator units exported by OpenModelica (../shared/outside/omsimulator):

* the units themselves, called through fmpy alone, take ``fmi2SetRealInputDerivatives`` of order 1 and answer order
  2 with ``fmi2Error``, though they declare ``canInterpolateInputs`` (FMI 2.0 declares no highest input order);
* a signal scene of their Co-Simulation at ``k = 2`` with inputs by derivatives is refused before any step, naming
  the unit, its attributes, the order, ``coupling.k`` and ``coupling.inputs`` and the three ways round it, and each
  of those ways runs; ``k = 1`` runs as before.
"""

from __future__ import annotations

import pytest
import yaml
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from test_signals_outside import OM, dmo_scene

from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import run_signal_scene
from icosim.problems.fmu.units import Unit

pytestmark = pytest.mark.outside

UNIT = OM / "DualMassOscillator.System1.fmu"


def test_the_openmodelica_unit_takes_first_order_input_derivatives_and_refuses_the_second(tmp_path):
    md = read_model_description(str(UNIT))
    assert md.coSimulation.canInterpolateInputs and md.coSimulation.maxOutputDerivativeOrder == 1
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(UNIT), str(tmp_path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="s1")  # fmt: skip
    fmu.instantiate()
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        force = next(v.valueReference for v in md.modelVariables if v.name == "F")
        fmu.setRealInputDerivatives([force], [1], [0.0])
        with pytest.raises(FMICallException) as refused:
            fmu.setRealInputDerivatives([force], [2], [0.0])
        assert refused.value.status == 3  # fmi2Error
    finally:
        fmu.freeInstance()


@pytest.fixture
def no_step(monkeypatch):
    """A refusal comes before any unit is stepped."""

    def stepped(*args, **kwargs):
        raise AssertionError("a unit was stepped")

    monkeypatch.setattr(Unit, "_do_step", stepped)


@pytest.mark.parametrize("inputs", ["derivatives", "auto"])
def test_order_two_input_derivatives_are_refused_by_name_before_any_step(tmp_path, no_step, inputs):
    path = dmo_scene(tmp_path, 1e-3, 0.01, k=2, inputs=inputs)
    with pytest.raises(SceneError) as refused:
        run_signal_scene(load_scene(path))
    text = str(refused.value)
    assert text.startswith(f"{path}: subsystems.system1: DualMassOscillator.System1.fmu (canInterpolateInputs=true, ")
    for part in ("maxOutputDerivativeOrder=1", "refuses fmi2SetRealInputDerivatives of order 2", "coupling.k: 2",
                 "coupling.inputs", "its input F", "coupling.inputs: substeps", "coupling.k: 1 or lower",
                 "subsystems.system1.interface: model-exchange"):  # fmt: skip
        assert part in text, text


def with_changes(path, coupling=None, subsystems=None):
    data = yaml.safe_load(path.read_text())
    data["coupling"].update(coupling or {})
    for name in subsystems or ():
        data["subsystems"][name].update(subsystems[name])
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(
    "coupling, subsystems",
    [
        ({"inputs": "substeps"}, None),
        ({"k": 1}, None),
        (None, {name: {"interface": "model-exchange"} for name in ("system1", "system2")}),
    ],
)
def test_each_way_round_it_runs(tmp_path, coupling, subsystems):
    path = with_changes(dmo_scene(tmp_path, 1e-3, 0.01, k=2, inputs="auto"), coupling, subsystems)
    run = run_signal_scene(load_scene(path))
    assert run.status == "completed" and abs(run.times[-1] - 0.01) < 1e-12
