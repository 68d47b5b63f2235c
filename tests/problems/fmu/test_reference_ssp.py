"""Systems of Reference-FMUs (../shared/outside/reference-fmus/fmus2) written as SSP 1.0 archives here, run by icosim
and by FMPy's own ``fmpy.ssp.simulate_ssp`` on the same files.

What FMPy's ``simulate_ssp`` does (fmpy/ssp/simulation.py): every connector starts at 0.0; each step sets every
unit's input connectors, calls ``doStep(time, step)`` on each unit, reads their output connectors, then copies each
connection's start connector to its end (Jacobi, inputs held: icosim's explicit Jacobi with ``k = 0``); it records a
row after each step stamped with the step's start time, and advances ``time += step`` while ``time < stop_time`` (so
a stop time that is a whole number of steps may take one step more, the sum's rounding).  It applies no linear
transformation and no parameter binding of the file.

So, with the same start, icosim and FMPy hand the units the same values and must agree to rounding; the one
documented difference is the start: icosim hands each input its connection's value at ``t0`` (the source's output),
FMPy 0.0.  From a zero start (the library call's coupling history) the two agree bit for bit; from its own start
icosim differs by the first step's input, an ``O(H)`` difference (it halves with ``H``).

Dahlquist (``x' = -k x``, no input) feeds the force input of fmus/msd (a mass on a spring-damper, exact over a
step): a one-way coupling, as Dahlquist has no input.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import ROOT
from toolchains import OUTSIDE

from icosim.engine.run import simulate
from icosim.problems.fmu.build import build_unit
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import run_signal_scene
from icosim.problems.fmu.signals import ForwardUnit, SignalCosimulation, connections_of

pytestmark = [pytest.mark.fmu, pytest.mark.outside]

REFERENCE = OUTSIDE / "reference-fmus" / "fmus2"


def write_ssp(path: Path, components: dict, connections: list) -> Path:
    """An SSP 1.0 archive: ``components`` name -> (.fmu file, {connector: kind}), ``connections`` (from, to) as
    ``unit.connector``."""
    elements = "".join(
        f'<ssd:Component name="{name}" type="application/x-fmu-sharedlibrary" source="resources/{name}.fmu">'
        "<ssd:Connectors>"
        + "".join(f'<ssd:Connector name="{c}" kind="{k}"><ssc:Real/></ssd:Connector>' for c, k in kinds.items())
        + "</ssd:Connectors></ssd:Component>"
        for name, (_, kinds) in components.items()
    )
    links = "".join(
        f'<ssd:Connection startElement="{a.split(".")[0]}" startConnector="{a.split(".", 1)[1]}" '
        f'endElement="{b.split(".")[0]}" endConnector="{b.split(".", 1)[1]}"/>'
        for a, b in connections
    )
    ssd = (
        '<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription version="1.0" name="system"'
        ' xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"'
        ' xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">'
        f'<ssd:System name="default"><ssd:Elements>{elements}</ssd:Elements>'
        f"<ssd:Connections>{links}</ssd:Connections></ssd:System></ssd:SystemStructureDescription>"
    )
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        for name, (fmu, _) in components.items():
            archive.write(fmu, f"resources/{name}.fmu")
    return path


@pytest.fixture(scope="module")
def dahlquist_msd(tmp_path_factory):
    msd = build_unit(ROOT / "fmus" / "msd", ROOT / "build" / "fmus")
    components = {"dahlquist": (REFERENCE / "Dahlquist.fmu", {"x": "output"}),
                  "mass": (msd, {"lambda": "input", "x": "output"})}  # fmt: skip
    path = write_ssp(tmp_path_factory.mktemp("ssp") / "dahlquist_msd.ssp", components, [("dahlquist.x", "mass.lambda")])
    return path, components


def fmpy_run(ssp: Path, H: float, t_end: float) -> np.ndarray:
    """FMPy's mass position after each step (its rows: after the step, stamped with its start)."""
    from fmpy.ssp.simulation import simulate_ssp

    return np.asarray(simulate_ssp(str(ssp), stop_time=t_end, step_size=H)["mass.x"])


def zero_start_run(components, H, n) -> np.ndarray:
    """icosim's explicit Jacobi with held inputs, its coupling history at t0 FMPy's start (every connector 0)."""
    names = list(components)
    cons, inputs, outputs = connections_of([("dahlquist", "x", "mass", "lambda", 1.0, 0.0)], names)
    outputs[1].append("x")
    units = [ForwardUnit(name, components[name][0], {k: v for k, v in (("signal_input", inputs[i]),
                         ("signal_output", outputs[i])) if v}, {}) for i, name in enumerate(names)]  # fmt: skip
    x = []
    try:
        problem = SignalCosimulation(units, inputs, outputs, cons, 0, H)
        history = problem.initial_history(np.zeros((1, problem.n_coupling)))
        simulate(problem, None, problem.initial_state(), history, n, record=False,
                 observe=lambda step, state, hist, y: x.append(units[1].get(("signal_output",)).ravel()[0]))  # fmt: skip
    finally:
        for unit in units:
            unit.close()
    return np.array(x)


def test_from_fmpys_start_icosim_is_fmpys_simulate_ssp_bit_for_bit(dahlquist_msd):
    ssp, components = dahlquist_msd
    H, t_end = 0.1, 10.0
    theirs = fmpy_run(ssp, H, t_end)
    ours = zero_start_run(components, H, round(t_end / H))
    assert len(theirs) in (len(ours), len(ours) + 1)  # the sum of the steps' rounding may take one step more
    np.testing.assert_array_equal(ours, theirs[: len(ours)])


def test_icosim_cosim_on_the_ssp_differs_from_fmpy_by_its_start_only(dahlquist_msd, tmp_path):
    """icosim's own start (the input at t0 the source's output, 1) against FMPy's (0): the mass's force differs by
    1 over the first step only, so the positions differ by the response to that pulse, at most ``H / (m w_d)``
    (msd's impulse response ``exp(-d t / 2 m) sin(w_d t) / (m w_d)``; its defaults m 1, c 1000, d 2)."""
    ssp, _ = dahlquist_msd
    m, c, d = 1.0, 1000.0, 2.0
    w_d = np.sqrt(c / m - (d / (2 * m)) ** 2)
    for H in (0.2, 0.1):  # whole multiples of Dahlquist's fixed step (its default experiment's 0.1 s)
        scene = tmp_path / f"scene_{H:g}.yaml"
        scene.write_text(yaml.safe_dump({"system": str(ssp), "coupling": {"H": H}, "t_end": 4.0}))
        run = run_signal_scene(load_scene(scene))
        ours = np.array(run.series["mass.x"][1:])
        theirs = fmpy_run(ssp, H, 4.0)[: len(ours)]
        gap = np.max(np.abs(ours - theirs))
        assert 0 < gap <= H / (m * w_d), (H, gap)
