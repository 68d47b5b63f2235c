"""Implicit coupling of signal connections (``coupling: {implicit: true}``): OMSimulator's DualMassOscillator
(../shared/outside/omsimulator, test_signals_outside's CONNECTIONS: ``system1.F <- system2.F``, ``system2.{x1, v1,
a1} <- system1.{x1, v1, a1}``) on its Model Exchange units, integrated by icosim far below the coupling's error.

What the tests compare follows from the method, not from numbers of the code under test:

* the reference is the exact solution of the linear Modelica equations of DualMassOscillator.mo
  (test_drives.exact, a matrix exponential);
* the connections' conditions are solved at ``T_N+1``, each unit integrated with the interpolation polynomial of
  order ``k`` through the new values and the past samples: the error is of order ``k + 1`` in ``H``;
* at an ``H`` where explicit Jacobi grows without bound (the free oscillation's amplitude exceeded while the
  physical one decays) the implicit run decays as the physical one does;
* the units are linear, so Newton from a difference-quotient Jacobian closes the conditions in one step up to the
  quotient's rounding: a second step at most to meet the tolerance, and the Jacobian costs one perturbed unit step
  per connection and macro step (it is formed once per step);
* --predict's spectral radius of the implicit recurrence (the built-in linear model on the identified units) is
  the decay per step the run shows;
* Gauss-Seidel closes the same conditions (the order moves Newton's start only, docs/signals.md): with a
  tolerance near rounding its runs are Jacobi's to rounding, in either order, and its order and predicted rho are
  Jacobi's;
* Co-Simulation units that cannot save their state (these units' ``canGetAndSetFMUstate`` is false), Newton that
  does not converge, and bad keys are refused by name.
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from helpers import FMU_CACHE
from test_drives import AMPLITUDE, MASS, MOVE, exact
from test_peers import dmo_ssp
from test_predict_signals import growth
from test_signal_scene import load
from test_signals_outside import CONNECTIONS, OM, model_exchange_error

from icosim.engine.connection_conditions import NotConverged
from icosim.order_fit import asymptotic_order
from icosim.problems.fmu.build import build_unit
from icosim.problems.fmu.errors import SceneError
from icosim.problems.fmu.predict_signals import predict_signal_scene
from icosim.problems.fmu.scene import load_scene
from icosim.problems.fmu.signal_scene import run_signal_scene, signal_dataset
from icosim.studies.peers.runners import DMO_UNITS


def dmo_scene(tmp_path, H, t_end, interface="model-exchange", **coupling):
    subs = {
        "system1": {"fmu": str(OM / DMO_UNITS["system1"]), "start": {"x1_start": 0.0}},
        "system2": {"fmu": str(OM / DMO_UNITS["system2"]), "start": {"x2_start": 0.5}, "record": ["mass2.s"]},
    }
    for sub in subs.values():
        if interface is not None:
            sub["interface"] = interface
    data = {
        "subsystems": subs,
        "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u, _, _ in CONNECTIONS],
        "coupling": {"H": H, **coupling},
        "t_end": t_end,
    }
    path = tmp_path / f"dmo_{H:g}_{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def positions(run):
    """x1 and x2 over the run, ``(len(times), 2)``."""
    return np.array([run.series["system1.x1"], run.series["system2.mass2.s"]]).T


@pytest.mark.parametrize("k", [0, 1])
def test_implicit_coupling_decays_where_explicit_jacobi_grows(tmp_path, k):
    """H = 0.2 s over 20 s: explicit Jacobi's oscillation grows past the start amplitude (the physical one decays:
    its dampers take energy); the implicit run stays below the start amplitude and decays with it; with k = 1 it
    stays near the exact solution (with k = 0 its first-order phase error at so large a step is of the amplitude's
    size)."""
    H, t_end = 0.2, 20.0
    explicit = run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=k)))
    implicit = run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=k, implicit=True)))
    ref = exact(implicit.times)[:, :2]
    assert np.max(np.abs(positions(explicit)[-10:])) > AMPLITUDE > np.max(np.abs(ref[-10:])) * 10
    x = positions(implicit)
    n = len(x) // 4
    assert np.max(np.abs(x[1:])) < AMPLITUDE and np.max(np.abs(x[-n:])) < 0.2 * AMPLITUDE  # decays
    if k == 1:
        assert np.max(np.abs(x - ref)) < 0.1 * AMPLITUDE


@pytest.mark.parametrize("k, scheme", [(0, "jacobi"), (1, "jacobi"), (0, "gauss-seidel-21"), (1, "gauss-seidel-21")])
def test_implicit_coupling_has_the_order_of_its_interpolation(k, scheme):
    """Gauss-Seidel closes the same conditions (its last stage all of them, every fed unit stepped again): the same
    order and cost."""
    Hs = [4e-3, 2e-3, 1e-3]
    results = [model_exchange_error(k, H, 1.0, scheme, implicit=True) for H in Hs]
    errors = [e for e, _ in results]
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - (k + 1)) < 0.2, (errors, fit)
    assert errors[-1] < (1e-2 if k == 0 else 1e-5) * AMPLITUDE, errors
    for H, (_, work) in zip(Hs, results):
        assert len(work.iterations) == round(1.0 / H) and max(work.iterations) <= 2, work.iterations[:10]
        assert work.perturbed_steps == len(CONNECTIONS) * round(1.0 / H)


GAUSS_SEIDEL = [
    {"scheme": "gauss-seidel", "order": ["system1", "system2"]},
    {"scheme": "gauss-seidel", "order": ["system2", "system1"]},
]


@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("scheme", GAUSS_SEIDEL)
def test_gauss_seidel_coupled_implicitly_is_jacobi_to_rounding(tmp_path, k, scheme):
    """The conditions at T_N+1, every unit's inputs the interpolation through the new values, are one system in
    those values whatever the order: Gauss-Seidel moves Newton's start only (the later unit fed by the earlier one's
    new output).  Converged to a tolerance near rounding, the runs agree to rounding; each Newton iteration
    steps every unit again, and the Jacobian costs what Jacobi's does."""
    H, t_end = 1e-2, 1.0
    runs = [run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=k, implicit=True, tol=1e-13, **how)))
            for how in ({}, scheme)]  # fmt: skip
    assert [run.status for run in runs] == ["completed"] * 2
    assert np.max(np.abs(positions(runs[1]) - positions(runs[0]))) <= 1e-13 * AMPLITUDE
    n = round(t_end / H)
    assert runs[1].jacobian_steps == runs[0].jacobian_steps == len(CONNECTIONS) * n
    # each unit saved once per step, by its first step (the later stage's unit: by its step on the new output)
    assert [runs[1].units[name]["states_saved"] for name in ("system1", "system2")] == [n, n]


def test_the_ssp_form_coupled_implicitly_follows_the_exact_solution_to_two_seconds(tmp_path):
    """OMSimulator's system of the DualMassOscillator as an SSP archive (its four connections), its units' Model
    Exchange interfaces chosen by the scene, coupled implicitly at H = 1e-3 with k = 2: the positions follow the exact
    solution within 1e-6 of the amplitude (the coupling's error of order 3 in H; with k = 1 it exceeds that bound).
    Two seconds hold the error's largest part: it peaks in the first half second and shrinks as the dampers take
    the oscillation's energy."""
    scene = tmp_path / "scene.yaml"
    me = {"interface": "model-exchange"}
    scene.write_text(yaml.safe_dump({"system": str(dmo_ssp(tmp_path / "DualMassOscillator.ssp")),
                                     "subsystems": {"system1": me, "system2": me},
                                     "coupling": {"H": 1e-3, "k": 2, "implicit": True}, "t_end": 2.0}))  # fmt: skip
    run = run_signal_scene(load_scene(scene))
    assert run.status == "completed" and run.times[-1] == pytest.approx(2.0)
    error = np.max(np.abs(positions(run) - exact(np.asarray(run.times))[:, :2]))
    assert error <= 1e-6 * AMPLITUDE, error


def test_the_dataset_says_implicit_and_counts_newton(tmp_path):
    H, t_end = 1e-2, 1.0
    run = run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=1, implicit=True)))
    ds = signal_dataset(run)
    n = round(t_end / H)
    assert ds.attrs["coupling"] == "implicit" and ds.attrs["newton_tol"] == 1e-10
    assert ds.attrs["newton_max_iterations"] == 10
    assert 1 <= ds.attrs["iterations_mean"] <= ds.attrs["iterations_max"] <= 2
    assert ds.attrs["jacobian_steps"] == len(CONNECTIONS) * n
    # saved once per step (the predictor), restored for the Jacobian's step (system1 takes one input) and the corrector
    assert ds.attrs["system1_states_saved"] == n and ds.attrs["system1_states_restored"] >= 2 * n
    explicit = signal_dataset(run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=1))))
    assert explicit.attrs["coupling"] == "explicit" and "jacobian_steps" not in explicit.attrs


def test_a_unit_that_cannot_save_its_state_is_refused_naming_it_and_the_fix(tmp_path):
    """These Co-Simulation units declare canGetAndSetFMUstate false: implicit coupling steps them again from T_N."""
    path = dmo_scene(tmp_path, 1e-2, 1.0, interface=None, implicit=True)
    with pytest.raises(SceneError) as refused:
        run_signal_scene(load_scene(path))
    text = str(refused.value)
    for says in ("subsystems.system1", "canGetAndSetFMUstate=false", "coupling.implicit", "interface: model-exchange",
                 "implicit: false"):  # fmt: skip
        assert says in text, text


def test_newton_that_does_not_converge_is_named_with_step_and_time(tmp_path):
    """One Newton step cannot meet a tolerance below the difference quotient's rounding."""
    path = dmo_scene(tmp_path, 1e-2, 1.0, implicit=True, iterations=1, tol=1e-15)
    with pytest.raises(NotConverged, match=r"macro step 1 \(from t = 0 s\).* did not converge in 1 iterations.*"
                       r"system\d\.\w+ -> system\d\.\w+ \(change"):  # fmt: skip
        run_signal_scene(load_scene(path))


@pytest.mark.parametrize("coupling, where, says", [
    ({"implicit": "yes"}, "coupling.implicit", "must be true or false"),
    ({"implicit": True, "iterations": 0}, "coupling.iterations", "integer >= 1"),
    ({"implicit": True, "iterations": 2.5}, "coupling.iterations", "integer >= 1"),
    ({"implicit": True, "tol": -1.0}, "coupling.tol", "must be > 0"),
    ({"implicit": True, "tol": "small"}, "coupling.tol", "finite number"),
    ({"iterations": 3}, "coupling.iterations", "belong to implicit: true"),
    ({"tol": 1e-8}, "coupling.tol", "belong to implicit: true"),
])  # fmt: skip
def test_bad_newton_keys_are_refused_naming_them(tmp_path, coupling, where, says):
    with pytest.raises(SceneError) as refused:
        load(tmp_path, coupling={"H": 0.1, **coupling})
    assert f"scene.yaml: {where}:" in str(refused.value) and says in str(refused.value), str(refused.value)


def test_implicit_defaults(tmp_path):
    c = load(tmp_path, coupling={"H": 0.1, "implicit": True}).coupling
    assert (c["iterations"], c["tol"]) == (10, 1e-10)


@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("scheme", [{}] + GAUSS_SEIDEL)
def test_the_prediction_of_implicit_coupling_is_the_decay_of_its_run(tmp_path, k, scheme):
    """--predict on an implicit scene: the recurrence of the identified units with the connections closed at T_N+1
    (the built-in linear model's implicit step): at H = 0.2 s stable where explicit Jacobi is not, and the run
    decays per step by the predicted rho (test_predict_signals' measure of growth, within 5 % of 1 - rho); Jacobi's
    and either Gauss-Seidel order's (the same conditions)."""
    H, steps = 0.2, 150
    path = dmo_scene(tmp_path, H, steps * H, k=k, implicit=True, **scheme)
    answer = predict_signal_scene(load_scene(path))
    mine = next(row for row in answer["schemes"] if row["scene"])
    explicit = next(row for row in answer["schemes"] if row["label"] == "Jacobi")
    assert mine["implicit"] and mine["verdict"] == "stable" and explicit["verdict"] == "unstable", answer["schemes"]
    assert answer["coupling"].startswith("implicit")
    rho = mine["rho"]
    measured = growth(run_signal_scene(load_scene(path)), steps)
    assert abs(measured - rho) <= 0.05 * (1 - rho), (measured, rho)


def built_dmo_scene(tmp_path, H, t_end, **coupling):
    """The DualMassOscillator as two Co-Simulation units built from fmus/ that save their state and step exactly
    with polynomial inputs: msd (mass 1, its spring and damper to the ground, driven by the force) and
    move_oscillator (OMSimulator's System2), coupled as OMSimulator's test couples them."""
    data = {
        "subsystems": {
            "mass1": {"fmu": str(build_unit(MASS["fmu"], FMU_CACHE)), "start": MASS["start"]},
            "system2": {"fmu": str(build_unit(MOVE["fmu"], FMU_CACHE)), "record": ["x2"]},
        },
        "connections": [{"from": "system2.F", "to": "mass1.lambda"}]
        + [{"from": f"mass1.{y}", "to": f"system2.{u}"} for y, u in (("x", "x1"), ("v", "v1"), ("a", "a1"))],
        "coupling": {"H": H, **coupling},
        "t_end": t_end,
    }
    path = tmp_path / f"built_{H:g}_{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("k", [0, 1])
def test_co_simulation_units_that_save_their_state_are_coupled_implicitly(tmp_path, k):
    """Their FMU states saved at T_N and restored for every further step: the coupling's order k + 1 against the
    exact solution (the units step exactly), the Jacobian one perturbed step per connection and step."""
    Hs, t_end = [4e-3, 2e-3, 1e-3], 1.0
    errors = []
    for H in Hs:
        run = run_signal_scene(load_scene(built_dmo_scene(tmp_path, H, t_end, k=k, implicit=True)))
        x = np.array([run.series["mass1.x"][-1], run.series["system2.x2"][-1]])
        errors.append(float(np.max(np.abs(x - exact([t_end])[0, :2]))))
        n = round(t_end / H)
        assert run.jacobian_steps == len(CONNECTIONS) * n and max(run.iterations) <= 2
        assert run.units["mass1"]["states_saved"] == n
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - (k + 1)) < 0.2, (errors, fit)


@pytest.mark.parametrize("order", [["mass1", "system2"], ["system2", "mass1"]])
def test_co_simulation_units_coupled_implicitly_by_gauss_seidel_give_jacobis_run(tmp_path, order):
    """The later stage's unit saves its state at its first step (on the earlier one's new output): the run is
    Jacobi's to rounding, each unit saved once per step."""
    H, t_end = 1e-2, 1.0
    runs = [run_signal_scene(load_scene(built_dmo_scene(tmp_path, H, t_end, k=1, implicit=True, tol=1e-13, **how)))
            for how in ({}, {"scheme": "gauss-seidel", "order": order})]  # fmt: skip
    x = [np.array([run.series["mass1.x"], run.series["system2.x2"]]).T for run in runs]
    assert np.max(np.abs(x[1] - x[0])) <= 1e-13 * AMPLITUDE
    assert [runs[1].units[name]["states_saved"] for name in order] == [round(t_end / H)] * 2


def test_the_built_units_and_omsimulators_give_one_implicit_run(tmp_path):
    """The same equations by two implementations (OMSimulator's Model Exchange units integrated by icosim at its
    default tolerance, the built units stepping exactly): the implicit runs agree far below the coupling's error."""
    H, t_end = 2e-3, 1.0
    ours = run_signal_scene(load_scene(built_dmo_scene(tmp_path, H, t_end, k=1, implicit=True)))
    theirs = run_signal_scene(load_scene(dmo_scene(tmp_path, H, t_end, k=1, implicit=True)))
    a = np.array([ours.series["mass1.x"], ours.series["system2.x2"]]).T
    b = positions(theirs)
    error = np.max(np.abs(b - exact(theirs.times)[:, :2]))
    assert np.max(np.abs(a - b)) < 1e-4 * error, (np.max(np.abs(a - b)), error)


@pytest.mark.parametrize("k", [0, 1])
def test_where_the_prediction_finds_implicit_coupling_unstable_the_run_grows_by_its_rho(tmp_path, k):
    """Implicit coupling with interpolated inputs is not stable at every H: at H = 0.7 s the recurrence of the
    identified units has rho > 1 (Newton still converges: the conditions hold at every point, the inputs between
    the points are the interpolation's), and the run grows per step by it."""
    H, steps = 0.7, 150
    path = dmo_scene(tmp_path, H, round(steps * H, 10), k=k, implicit=True)
    mine = next(row for row in predict_signal_scene(load_scene(path))["schemes"] if row["scene"])
    rho = mine["rho"]
    assert mine["verdict"] == "unstable" and rho > 1.01, mine
    run = run_signal_scene(load_scene(path))
    assert run.status == "completed" and max(run.iterations) <= 3
    measured = growth(run, steps)
    assert abs(measured - rho) <= 0.05 * (rho - 1), (measured, rho)


@pytest.mark.parametrize("k", [0, 1])
def test_the_largest_stable_h_stops_below_the_band_where_implicit_coupling_grows(tmp_path, k):
    """The band of H where implicit coupling of these units is unstable (the run at 0.7 s grows, test above) is
    narrower than a decade: the largest stable H predicted from a scene at H = 0.01 s is its lower edge, below 0.7 s
    and above the scene's H, bisected, not censored at the scan's cap."""
    limit = predict_signal_scene(load_scene(dmo_scene(tmp_path, 0.01, 1.0, k=k, implicit=True)))["largest_stable_H"]
    assert limit["status"] == "bisected" and 0.01 < limit["H_max"] < limit["H_unstable"] < 0.7, limit
    assert limit["H_unstable"] / limit["H_max"] < 1.01 and limit["scan_ratio"] < 1.1, limit
