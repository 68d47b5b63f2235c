"""The DualMassOscillator's exact solution (icosim.problems.fmu.dual_mass) against an independent integration of
the Modelica equations (ReferenceSystemEq, written out here as two second-order equations), its connected outputs
against System1's and System2's own equations, and its parameters as the Modelica source and the units' model
descriptions declare them."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from toolchains import OUTSIDE

from icosim.problems.fmu.dual_mass import DualMass

OM = OUTSIDE / "omsimulator"
# DualMassOscillator.mo, ReferenceSystemEq: the values as the source writes them
MODELICA = dict(m1=1.0, k1=10.0, c1=0.2, m2=1.0, k2=10.0, c2=0.5, k3=20.0, c3=0.3, x1_start=0.0, x2_start=0.5)


def reference_eq(p):
    def rhs(t, z):
        x1, x2, v1, v2 = z
        a1 = -((p.c1 + p.c2) * v1 - p.c2 * v2 + (p.k1 + p.k2) * x1 - p.k2 * x2) / p.m1
        a2 = -(-p.c2 * v1 + (p.c2 + p.c3) * v2 - p.k2 * x1 + (p.k2 + p.k3) * x2) / p.m2
        return [v1, v2, a1, a2]

    return rhs


@pytest.mark.parametrize("params", [MODELICA, dict(MODELICA, m2=3.0, c3=0.0, x1_start=-0.2)])
def test_the_exact_solution_is_the_reference_system_integrated(params):
    p = DualMass(**params)
    t = np.linspace(0.0, 3.0, 31)
    ref = solve_ivp(reference_eq(p), (0.0, 3.0), p.start, method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t).y.T
    assert np.max(np.abs(p.exact(t) - ref)) < 1e-10 * p.amplitude


def test_the_exact_solution_runs_backwards_from_the_start():
    """The coupling history before ``t = 0`` (``T_-1 ... T_-k``) is the same solution at negative times."""
    p = DualMass(**MODELICA)
    back = solve_ivp(reference_eq(p), (0.0, -0.01), p.start, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    assert np.max(np.abs(p.exact([-0.01])[0] - back)) < 1e-12


def test_the_outputs_satisfy_the_units_equations():
    """System1: m1 a1 = F - k1 x1 - c1 v1 (F its input); System2: F = k2 (x2 - x1) + c2 (v2 - v1), and mass 2
    moves as m2 a2 = -k3 x2 - c3 v2 - F (the sensor's force taken from it)."""
    p = DualMass(**MODELICA)
    for t in (0.0, 0.37, 1.9):
        y = p.outputs(t)
        x1, x2, v1, v2 = p.exact([t])[0]
        assert y["system1.x1"] == x1 and y["system1.v1"] == v1 and y["system2.mass2.s"] == x2
        assert p.m1 * y["system1.a1"] == pytest.approx(y["system2.F"] - p.k1 * x1 - p.c1 * v1, abs=1e-13)
        h = 1e-5
        a2 = (p.exact([t + h])[0, 3] - p.exact([t - h])[0, 3]) / (2 * h)
        assert p.m2 * a2 == pytest.approx(-p.k3 * x2 - p.c3 * v2 - y["system2.F"], abs=1e-8)


def test_bad_parameters_are_refused_naming_them():
    with pytest.raises(ValueError, match="m2"):
        DualMass(m2=0.0)
    with pytest.raises(ValueError, match="k3"):
        DualMass(k3=float("nan"))


@pytest.mark.outside
def test_the_parameters_are_those_of_the_modelica_source_and_of_the_units():
    from_source = DualMass.from_modelica(OM / "DualMassOscillator.mo")
    from_units = DualMass.from_units(OM / "DualMassOscillator.System1.fmu", OM / "DualMassOscillator.System2.fmu")
    assert from_source == from_units == DualMass(**MODELICA)
    moved = DualMass.from_units(OM / "DualMassOscillator.System1.fmu", OM / "DualMassOscillator.System2.fmu",
                                {"system2": {"x2_start": 0.25, "k3": 5.0}})  # fmt: skip
    assert moved.x2_start == 0.25 and moved.k3 == 5.0 and moved.k2 == MODELICA["k2"]


@pytest.mark.outside
def test_a_model_the_source_lacks_is_named():
    with pytest.raises(ValueError, match="no model Nowhere"):
        DualMass.from_modelica(OM / "DualMassOscillator.mo", "Nowhere")
