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
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from helpers import FMU_CACHE, ROOT
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
    msd = build_unit(ROOT / "fmus" / "msd", FMU_CACHE)
    components = {"dahlquist": (REFERENCE / "Dahlquist.fmu", {"x": "output"}),
                  "mass": (msd, {"lambda": "input", "x": "output"})}  # fmt: skip
    path = write_ssp(tmp_path_factory.mktemp("ssp") / "dahlquist_msd.ssp", components, [("dahlquist.x", "mass.lambda")])
    return path, components


def fmpy_run(ssp: Path, H: float, t_end: float, read: str = "mass.x", starts: dict | None = None) -> np.ndarray:
    """FMPy's connector ``read`` after each step (its rows: after the step, stamped with its start); ``starts``:
    ``unit.variable`` -> value, FMPy's ``parameter_set`` (it applies no binding of the file)."""
    from fmpy.ssp.simulation import simulate_ssp

    given = None
    if starts:
        given = SimpleNamespace(parameters=[SimpleNamespace(name=n, value=v) for n, v in starts.items()])
    return np.asarray(simulate_ssp(str(ssp), stop_time=t_end, step_size=H, parameter_set=given)[read])


def zero_start_run(components, connections, read, H, n, starts=None) -> dict:
    """icosim's explicit Jacobi with held inputs, its coupling history at t0 FMPy's start (every connector 0):
    the outputs ``read`` (``unit.output``) after each step; ``starts`` as :func:`fmpy_run`'s."""
    names = list(components)
    specs = [(*a.split("."), *b.split("."), 1.0, 0.0) for a, b in connections]
    cons, inputs, outputs = connections_of(specs, names)
    for ref in read:
        unit, name = ref.split(".")
        if name not in outputs[names.index(unit)]:
            outputs[names.index(unit)].append(name)
    given = {name: {} for name in names}
    for ref, value in (starts or {}).items():
        given[ref.split(".")[0]][ref.split(".", 1)[1]] = value
    units = [ForwardUnit(name, components[name][0], {k: v for k, v in (("signal_input", inputs[i]),
                         ("signal_output", outputs[i])) if v}, given[name]) for i, name in enumerate(names)]  # fmt: skip
    values: dict = {ref: [] for ref in read}

    def observe(step, state, hist, y):
        for ref in read:
            unit, name = ref.split(".")
            i = names.index(unit)
            values[ref].append(units[i].get(("signal_output",)).ravel()[outputs[i].index(name)])

    try:
        problem = SignalCosimulation(units, inputs, outputs, cons, 0, H)
        history = problem.initial_history(np.zeros((1, problem.n_coupling)))
        simulate(problem, None, problem.initial_state(), history, n, record=False, observe=observe)
    finally:
        for unit in units:
            unit.close()
    return {ref: np.array(v) for ref, v in values.items()}


def test_from_fmpys_start_icosim_is_fmpys_simulate_ssp_bit_for_bit(dahlquist_msd):
    ssp, components = dahlquist_msd
    H, t_end = 0.1, 10.0
    theirs = fmpy_run(ssp, H, t_end)
    ours = zero_start_run(components, [("dahlquist.x", "mass.lambda")], ["mass.x"], H, round(t_end / H))["mass.x"]
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


#: VanDerPol's position as the reference a proportional controller (fmus/pcontrol, u = kp (r - y)) makes fmus/msd's
#: mass follow: a feedback loop between the controller and the mass (the mass's position depends on no input at
#: once, so no algebraic loop), VanDerPol feeding it (it has no input).
VDP_CONNECTIONS = [("vdp.x0", "control.r"), ("mass.x", "control.y"), ("control.u", "mass.lambda")]
#: A gain and a damping under which the loop, delayed a step by the held inputs, stays stable at H = 1e-2.
VDP_STARTS = {"control.kp": 100.0, "mass.d": 20.0}


@pytest.fixture(scope="module")
def vanderpol_control(tmp_path_factory):
    msd = build_unit(ROOT / "fmus" / "msd", FMU_CACHE)
    control = build_unit(ROOT / "fmus" / "pcontrol", FMU_CACHE)
    components = {"vdp": (REFERENCE / "VanDerPol.fmu", {"x0": "output"}),
                  "control": (control, {"r": "input", "y": "input", "u": "output"}),
                  "mass": (msd, {"lambda": "input", "x": "output"})}  # fmt: skip
    path = write_ssp(tmp_path_factory.mktemp("ssp") / "vanderpol_control.ssp", components, VDP_CONNECTIONS)
    return path, components


def test_a_controlled_van_der_pol_from_fmpys_start_is_fmpys_simulate_ssp_bit_for_bit(vanderpol_control):
    ssp, components = vanderpol_control
    H, t_end = 1e-2, 5.0
    ours = zero_start_run(components, VDP_CONNECTIONS, ["mass.x", "control.u"], H, round(t_end / H), VDP_STARTS)
    for ref in ("mass.x", "control.u"):
        theirs = fmpy_run(ssp, H, t_end, ref, VDP_STARTS)
        assert len(theirs) in (len(ours[ref]), len(ours[ref]) + 1)
        np.testing.assert_array_equal(ours[ref], theirs[: len(ours[ref])])
    x = ours["mass.x"]
    assert 0.1 < np.ptp(x) and np.max(np.abs(x)) < 1.0  # the mass follows (not zeros) and the loop stays stable


def test_icosim_cosim_on_the_controlled_van_der_pol_meets_fmpy_once_the_start_has_died_out(vanderpol_control,
                                                                                          tmp_path):  # fmt: skip
    """``icosim cosim`` on a scene naming the .ssp with the starts per component: its start (the reference 2, the
    Van der Pol's x0 at t0) differs from FMPy's (0) over the first step; VanDerPol has no input, the controller no
    state, and the mass's loop damps the difference (its rate about d / 2m = 10 per s), so after 5 s the two runs
    agree to rounding."""
    from icosim.cli import main
    from icosim.io.netcdf import open_dataset

    ssp, _ = vanderpol_control
    H, t_end = 1e-2, 5.0
    scene = tmp_path / "scene.yaml"
    subs = {"control": {"start": {"kp": VDP_STARTS["control.kp"]}}, "mass": {"start": {"d": VDP_STARTS["mass.d"]}}}
    scene.write_text(yaml.safe_dump({"system": str(ssp), "subsystems": subs, "coupling": {"H": H}, "t_end": t_end}))
    out = tmp_path / "run.nc"
    assert main(["cosim", str(scene), "--out", str(out)]) == 0
    ours = open_dataset(out)["mass.x"].values[1:]
    theirs = fmpy_run(ssp, H, t_end, "mass.x", VDP_STARTS)[: len(ours)]
    gap = np.abs(ours - theirs)
    assert gap[:10].max() > 1e-4 and gap[-1] <= 1e-12 * np.max(np.abs(theirs)), (gap[:10].max(), gap[-1])
