"""Macro steps sized by ECCO's power residual (``coupling.control: {estimate: power-residual}``), on OSP's quarter
truck (../shared/outside/osp-quarter-truck: libcosim's test data, its ``OspSystemStructure.xml`` asks for ECCO).

* the file's ``EccoConfiguration`` becomes the run's control, and a control with keys of the other estimate, an
  unknown estimate or without its tolerance is refused naming the key, before any unit is opened;
* the controlled run accepts and rejects steps, keeps them within the file's bounds, and the power residual and
  the error norm it reports are recomputed here from the dataset's forces and velocities;
* the residual icosim sees is the units' own integration (the chassis's explicit Euler: its velocity output runs
  ahead of the velocity its position moves with by ``h a / 2``), not the coupling: it halves with the units' step;
* its error against a reference (icosim at fixed H = 2e-6 s, whose own error is bounded by halving it) shrinks as
  the power tolerance tightens;
* libcosim's ECCO run of the same file (libcosimpy, the ``test`` extra): its step sizes are those icosim's
  controller gives from libcosim's own residuals (to libcosim's nanosecond clock); the two masters' fixed-step
  references agree within their own errors (each bounded by halving its step) and resolve both ECCO runs' errors.
"""

import json

import numpy as np
import pytest
import yaml
from toolchains import OUTSIDE

from icosim.engine.control.controller import ecco_controller, power_residual_estimate
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.run import run_dataset_data, run_scene
from icosim.problems.fmu.scene import load_scene

pytestmark = pytest.mark.outside

OSP = OUTSIDE / "osp-quarter-truck"
#: the file's EccoConfiguration, as its text says
ECCO = {"SafetyFactor": 0.99, "StepSize": 1e-4, "MinimumStepSize": 1e-5, "MaximumStepSize": 0.01,
        "MinimumChangeRate": 0.2, "MaximumChangeRate": 1.5, "ProportionalGain": 0.2, "IntegralGain": 0.15,
        "RelativeTolerance": 1e-6, "AbsoluteTolerance": 1e-6}  # fmt: skip
#: icosim's reference steps (s): a run and its half
REFERENCE_H = (4e-6, 2e-6)
SWEEP_T_END = 0.02


def overlay(tmp_path, name, **keys):
    path = tmp_path / name
    path.write_text(yaml.safe_dump({"system": str(OSP / "OspSystemStructure.xml"), **keys}))
    return path


def fixed(H, mu=1e-4):
    """The systems' default coupling (Baumgarte index 1, k = 1, Jacobi) at a fixed ``H``, ``mu`` in s."""
    return {"method": "baumgarte", "index": 1, "mu": mu, "k": 1, "scheme": "jacobi", "H": H}


def test_the_osp_file_runs_with_its_ecco_configuration():
    scene = load_scene(OSP)
    c = scene.data["coupling"]
    assert c["H"] == ECCO["StepSize"]
    assert c["control"] == {
        "estimate": "power-residual", "H_min": 1e-5, "H_max": 0.01, "safety": 0.99, "fac_min": 0.2, "fac_max": 1.5,
        "proportional_gain": 0.2, "integral_gain": 0.15, "relative_tolerance": 1e-6, "absolute_tolerance": 1e-6,
    }  # fmt: skip
    (note,) = [n for n in scene.system.notes if "ECCO" in n]
    assert "run as coupling.control" in note and "not used" not in note


@pytest.mark.parametrize(
    "control, match",
    [
        ({"estimate": "power-residual", "tolerance": 1e-6, "absolute_tolerance": 1e-6, "H_min": 1e-5, "H_max": 1e-2},
         r"coupling.control.tolerance: not a key of the power-residual estimate; its keys: estimate, H_min, H_max, "
         r"safety, fac_min, fac_max, absolute_tolerance, relative_tolerance, proportional_gain, integral_gain"),
        ({"estimate": "power-residual", "H_min": 1e-5, "H_max": 1e-2},
         r"coupling.control: the power-residual estimate needs absolute_tolerance"),
        ({"estimate": "ecco", "absolute_tolerance": 1e-6, "H_min": 1e-5, "H_max": 1e-2},
         r"coupling.control.estimate: 'ecco' is not allowed; allowed: predictor-corrector, power-residual"),
        ({"absolute_tolerance": 1e-6, "tolerance": 1e-6, "H_min": 1e-5, "H_max": 1e-2},
         r"coupling.control.absolute_tolerance: not a key of the predictor-corrector estimate"),
        ({"estimate": "power-residual", "absolute_tolerance": 1e-6, "H_min": 1e-5, "H_max": 1e-2, "fac_max": 0.5},
         r"coupling.control: controller needs 0 < safety <= 1 and 0 < fac_min < 1 < fac_max"),
    ],
)  # fmt: skip
def test_a_bad_control_is_refused_naming_the_key(tmp_path, control, match):
    with pytest.raises(SceneError, match=match):
        load_scene(overlay(tmp_path, "bad.yaml", coupling={**fixed(1e-4), "control": control}))


@pytest.fixture(scope="module")
def ecco_run(tmp_path_factory):
    """The OSP file's own run (its ECCO configuration) over 0.05 s: the run and its dataset."""
    run = run_scene(overlay(tmp_path_factory.mktemp("ecco"), "osp.yaml", t_end=0.05))
    return run, run_dataset_data(run)


def test_the_controlled_run_accepts_and_rejects_steps_within_the_file_s_bounds(ecco_run):
    run, data = ecco_run
    assert run.status == "completed" and data.attrs["control_estimate"] == "power-residual"
    H = np.asarray(data.array("macro_step_size"))[1:]
    assert data.attrs["control_accepted_steps"] == len(H) > 0 and data.attrs["control_rejected_steps"] > 0
    assert np.isclose(np.sum(H), 0.05, rtol=0, atol=1e-12)
    lo, hi = ECCO["MinimumStepSize"], ECCO["MaximumStepSize"]
    assert np.all(H >= lo * (1 - 1e-12)) and np.all(H <= hi)
    assert all(lo * (1 - 1e-12) <= h <= hi for h in run.steps.rejected_H)
    assert len(np.unique(np.round(H, 15))) > 10  # the steps changed size
    assert json.loads(data.attrs["system_json"])["ecco"] == ECCO


def test_the_power_residual_it_reports_is_recomputed_from_the_dataset(ecco_run):
    """Per joint ``f_a v_a + f_b v_b``: the chassis's coupling force is its ``force`` input as read from the unit
    (the joint's multiplier, force_sign +1), the wheel's is its reaction, and the velocities are the motion rows
    (the wheel's: its driven point's).  The error norm is ECCO's ``E / (atol + rtol E)`` of the one bond's energy
    residual ``E = |r| H``, at most 1 on every accepted step."""
    _, data = ecco_run
    f, v = np.asarray(data.array("coupling_force")), np.asarray(data.array("velocity"))
    np.testing.assert_array_equal(f[0, 1:], np.asarray(data.array("chassis.force"))[1:])
    np.testing.assert_array_equal(v[0], np.asarray(data.array("chassis.velocity")))
    np.testing.assert_allclose(f[0, 1:], np.ravel(data.array("joint_force"))[1:], rtol=1e-12)
    np.testing.assert_allclose(f[1, 1:], -f[0, 1:], rtol=1e-9)  # the force balance holds at each step's end
    r = f[0] * v[0] + f[1] * v[1]
    reported = np.ravel(data.array("power_residual"))
    np.testing.assert_allclose(reported[1:], r[1:], rtol=1e-12, atol=1e-12 * np.max(np.abs(f[:, 1:] * v[:, 1:])))
    E = np.abs(r[1:]) * np.asarray(data.array("macro_step_size"))[1:]
    atol, rtol = ECCO["AbsoluteTolerance"], ECCO["RelativeTolerance"]
    norm = np.asarray(data.array("control_error"))[1:]
    np.testing.assert_allclose(norm, E / (atol + rtol * E), rtol=1e-9)
    assert np.all(norm <= 1.0) and np.max(norm) > 0.5  # the controller works near its target, err ~ 0.94


def test_the_residual_icosim_sees_is_the_chassis_s_own_euler(tmp_path):
    """The implicit joint makes the multiplier the wheel's reaction at every communication point and keeps the two
    positions together (gap ~ 1e-9 m), so what remains of ``f_a v_a + f_b v_b`` is ``lambda (v_a - v_b)``: the
    chassis's velocity output against the driven point's, which follows the chassis's position.  Explicit Euler at
    the unit's step ``h`` moves the position with the velocity of each step's start, so over a step the position
    moves with the mean of the two ends' velocities less ``h a / 2``: the velocity output leads by ``h a / 2``.  At
    a sub-step of 2e-5 s (H = 3.2e-4 s, 16 sub-steps: a whole number of the unit's steps) that holds for
    ``timeStep`` 1e-5 and 5e-6 s, and the residual halves with it."""
    H, t_end, r = 3.2e-4, 0.0192, {}
    for h in (1e-5, 5e-6):
        subs = {"chassis": {"start": {"timeStep": h}}}
        data = run_dataset_data(run_scene(overlay(tmp_path, f"h{h:g}.yaml", t_end=t_end, coupling=fixed(H, mu=H),
                                                  subsystems=subs)))  # fmt: skip
        lam, v = np.ravel(data.array("joint_force")), np.asarray(data.array("velocity"))
        a = np.asarray(data.array("acceleration"))[0, -1]
        lead = v[0, -1] - v[1, -1]
        assert abs(lead / (h * a / 2) - 1) < 0.05, (h, lead, h * a / 2)
        r[h] = lam[-1] * lead
    assert abs(r[1e-5] / r[5e-6] - 2) < 0.04, r


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """icosim at fixed ``REFERENCE_H`` over ``SWEEP_T_END``: the finer run's chassis position and the bound of its
    error, the change from the coarser (first order at least: the finer's error is at most the change)."""
    where = tmp_path_factory.mktemp("reference")
    runs = [run_scene(overlay(where, f"ref{h:g}.yaml", t_end=SWEEP_T_END, coupling=fixed(h))) for h in REFERENCE_H]
    coarse, fine = (r.positions[:, 0, 0] for r in runs)
    return runs[1].times, fine, float(np.max(np.abs(coarse - fine[::2])))


def control_run(tmp_path, name, atol, t_end=SWEEP_T_END, H_min=1e-6):
    control = {"estimate": "power-residual", "absolute_tolerance": atol, "H_min": H_min, "H_max": 1e-2}
    return run_scene(overlay(tmp_path, name, t_end=t_end, coupling={**fixed(1e-4), "control": control}))


def test_the_error_shrinks_as_the_power_tolerance_tightens(tmp_path, reference):
    t_ref, x_ref, ref_error = reference
    errors, steps = [], []
    for atol in (1e-4, 1e-5, 1e-6, 1e-7):
        run = control_run(tmp_path, f"atol{atol:g}.yaml", atol)
        assert run.status == "completed"
        x = np.interp(t_ref, run.times, run.positions[:, 0, 0])
        errors.append(np.max(np.abs(x - x_ref)))
        steps.append(len(run.steps.H))
    assert np.all(np.diff(errors) < 0), errors
    assert np.all(np.diff(steps) > 0), steps
    assert ref_error < errors[-1] / 3, (ref_error, errors)  # the reference's own error is well below each


def libcosim_run(where, xml, t_end):
    """libcosim on ``xml`` (the units linked beside it) to ``t_end``: the times and, per name, the chassis's
    ``position``, ``velocity`` and the wheel's ``out_spring_damper_f`` after each step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    where.mkdir()
    for unit in ("Chassis.fmu", "Wheel.fmu"):
        (where / unit).symlink_to(OSP / unit)
    (where / "OspSystemStructure.xml").write_text(xml)
    execution = CosimExecution.from_osp_config_file(osp_path=str(where))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    index = {s.name.decode(): s.index for s in execution.slave_infos()}
    refs = {n: {v.name.decode(): v.reference for v in execution.slave_variables(slave_index=i)}
            for n, i in index.items()}  # fmt: skip
    wanted = (("chassis", "position"), ("chassis", "velocity"), ("wheel", "out_spring_damper_f"))

    def read():
        return [observer.last_real_values(slave_index=index[u], variable_references=[refs[u][v]])[0] for u, v in wanted]

    times, values = [0.0], [read()]
    while times[-1] < t_end - 1e-12:
        execution.step()
        times.append(execution.status().current_time * 1e-9)
        values.append(read())
    x, v, F = np.array(values).T
    return np.array(times), {"position": x, "velocity": v, "force": F}


def test_libcosim_s_ecco_steps_are_icosim_s_controller_on_libcosim_s_residuals(tmp_path):
    """libcosim holds each input over the step and reads the bond after it: the chassis's power is its input
    ``F(T_N)`` (the wheel's force at the step's start) times its velocity ``v(T_N+1)``, the wheel's its input
    ``v(T_N)`` times its force ``F(T_N+1)``.  From that residual, icosim's norm and ECCO controller give libcosim's
    every next step (libcosim adjusts from its second step on, with a previous error of 1 at first) to its clock's
    nanosecond."""
    pytest.importorskip("libcosimpy")
    T, y = libcosim_run(tmp_path / "libcosim", (OSP / "OspSystemStructure.xml").read_text(), 0.05)
    H, v, F = np.diff(T), y["velocity"], y["force"]
    r = F[:-1] * v[1:] - v[:-1] * F[1:]  # the residual after each step
    ctl = ecco_controller(safety=0.99, fac_min=0.2, fac_max=1.5, proportional_gain=0.2, integral_gain=0.15,
                          H_min=1e-5, H_max=1e-2)  # fmt: skip
    err = [power_residual_estimate([r[n]], H[n], 1e-6, 1e-6) for n in range(len(H))]
    assert H[0] == H[1] == ECCO["StepSize"]
    predicted = [ctl.after_accept(H[n], err[n], 1.0 if n == 1 else err[n - 1]) for n in range(1, len(H) - 1)]
    assert len(predicted) > 1000
    np.testing.assert_allclose(predicted, H[2:], rtol=0, atol=1.01e-9)


def test_icosim_s_and_libcosim_s_references_agree_and_resolve_both_ecco_runs(tmp_path, reference):
    """Each master's error estimated from its own runs: icosim's ECCO run against its reference (fixed H = 2e-6 s,
    error bound: the change from 4e-6 s), libcosim's against its fixed-step run at 1.25e-6 s (error bound: the
    change from 2.5e-6 s, first order: explicit Jacobi with held inputs).  Both references converge to the same
    units' solution (the units' own Euler steps shrink with the communication step in both), so they must agree
    within the sum of their bounds (twice, for Richardson's leading order); each ECCO run's error must exceed its
    reference's bound, so that the difference of the two ECCO runs is the two masters' errors."""
    pytest.importorskip("libcosimpy")
    t_ref, x_ref, ref_error = reference
    t_end = SWEEP_T_END
    xml = (OSP / "OspSystemStructure.xml").read_text()
    T, y = libcosim_run(tmp_path / "ecco", xml, t_end)
    theirs_ecco = np.interp(t_ref, T, y["position"])
    fixed_xml = xml.replace("<Algorithm>ecco</Algorithm>", "<Algorithm>fixedStep</Algorithm>")
    theirs = {}
    for h in (2.5e-6, 1.25e-6):
        Th, yh = libcosim_run(
            tmp_path / f"fixed{h:g}", fixed_xml.replace("0.0001</BaseStepSize>", f"{h!r}</BaseStepSize>"), t_end
        )
        theirs[h] = np.interp(t_ref, Th, yh["position"])
    their_ref_error = np.max(np.abs(theirs[2.5e-6] - theirs[1.25e-6]))
    references_differ = np.max(np.abs(theirs[1.25e-6] - x_ref))
    assert references_differ <= 2 * (ref_error + their_ref_error), (references_differ, ref_error, their_ref_error)
    ours = control_run(tmp_path, "file.yaml", ECCO["AbsoluteTolerance"], t_end, ECCO["MinimumStepSize"])
    ours_ecco = np.interp(t_ref, ours.times, ours.positions[:, 0, 0])
    our_error = np.max(np.abs(ours_ecco - x_ref)) + ref_error
    their_error = np.max(np.abs(theirs_ecco - theirs[1.25e-6])) + their_ref_error
    # each ECCO run's error is resolved by its master's reference
    assert (
        np.max(np.abs(ours_ecco - x_ref)) > ref_error
        and np.max(np.abs(theirs_ecco - theirs[1.25e-6])) > their_ref_error
    )
    print(
        f"icosim ECCO error {our_error:.3g} m in {len(ours.steps.H)} steps ({ours.steps.n_rejected} rejected), "
        f"libcosim ECCO error {their_error:.3g} m in {len(T) - 1} steps, the two differ by "
        f"{np.max(np.abs(ours_ecco - theirs_ecco)):.3g} m, the references by {references_differ:.3g} m"
    )
    # the steps: icosim's residual is its units' Euler over a sub-step (H/16), libcosim's the held inputs' over H
    assert np.median(ours.steps.H) > np.median(np.diff(T))


def test_a_scene_s_own_coupling_replaces_the_file_s_ecco_control(tmp_path):
    scene = load_scene(overlay(tmp_path, "own.yaml", coupling=fixed(1e-4)))
    assert scene.data["coupling"].get("control") is None
    assert "ECCO step control and the scene's coupling replaces it: icosim couples at the fixed H = 0.0001 s" in (
        " ".join(scene.system.notes)
    )
