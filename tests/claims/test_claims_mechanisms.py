"""The mechanisms the claims' notes give, checked with the engine at the points they name.

Each note in config/claims/*.yaml that explains a verdict with a number or a cause is checked
here (or in the test named in the note): the number from the engine at 40 digits, not copied
from a dataset.
"""

import pytest

from icosim import TestModel, make_method
from icosim.problems.linear.model import PhysicalModel
from icosim.problems.linear.spectral import spectral_radius_mp

BAUMGARTE_1 = make_method("baumgarte", index=1, mu=1)


def rho(model, method, dec, k, scheme="jacobi"):
    return float(spectral_radius_mp(model, method, dec, k, digits=40, scheme=scheme))


def test_fig9_row4_k2_is_weakly_unstable_on_and_next_to_the_undamped_axis():
    """fig9_k2_stable_near_origin: on the axis lr1 = 0, rho - 1 is about 2.4e-4 near li1 = 0.1 and turns
    negative before li1 = 0.116; at lr1 = -1e-5, far inside one zoom spacing (0.004), rho > 1 still, while
    the zoom's first damped column lr1 = -0.004 is stable."""
    row4 = dict(am21=1, alr21=1, ali21=10)
    on_axis = rho(TestModel(0, 0.096, **row4), BAUMGARTE_1, "ff", 2) - 1
    assert 2.3e-4 < on_axis < 2.5e-4
    assert rho(TestModel(0, 0.116, **row4), BAUMGARTE_1, "ff", 2) < 1
    assert rho(TestModel(-1e-5, 0.1, **row4), BAUMGARTE_1, "ff", 2) > 1 + 2e-4
    assert rho(TestModel(-0.004, 0.1, **row4), BAUMGARTE_1, "ff", 2) < 1


@pytest.mark.parametrize("method", [make_method("baumgarte", index=3), make_method("baumgarte", index=2, mu=1e-3)])
def test_convergence_model_at_small_H_has_the_added_mass_eigenvalue(method):
    """gs12_heavier_corrected_index23_unstable: the convergence model (m2 = 2 m1) at H = 1e-6 s is close to
    free masses, and Gauss-Seidel 1->2 (the heavier subsystem corrected) has rho near m_2/m_1 = 2 at k = 0;
    2->1 (the lighter corrected) is not unstable."""
    from icosim.engine.methods import engine_method

    model = PhysicalModel(m1=1.0, m2=2.0, c1=1000.0, c2=1000.0, d1=10.0, d2=10.0, H=1e-6)
    engine = engine_method(method, 1e-6)
    assert rho(model, engine, "ff", 0, "gauss-seidel-12") == pytest.approx(2.0, abs=1e-3)
    assert rho(model, engine, "ff", 0, "gauss-seidel-21") <= 1 + 1e-12


@pytest.mark.parametrize(
    "method, dec_a, dec_b",
    [(make_method("weighted", a=1, b=1), "fd", "ff"), (make_method("projection"), "fd", "ff")],
    ids=["fig13-vs-10", "fig14-vs-11"],
)
def test_disagreements_with_the_paper_are_confirmed_by_time_stepping(method, dec_a, dec_b):
    """fd_vs_ff_weighted_k0 and fig14_similar_to_fig11 (row 1, k = 0): at the points of a coarse grid where
    force/displacement is unstable and force/force stable, plain time stepping grows by rho per macro step
    in fd (within 2 %) and does not grow in ff: the verdicts are the recurrence's, not the spectral radius
    routine's."""
    import numpy as np
    from helpers import growth_rate

    from icosim.problems.linear.problem import LinearCosimulation
    from icosim.problems.linear.spectral import spectral_radius_float64

    found = []  # (lr1, li1, rho_a)
    for lr1 in np.linspace(-1.9, -0.1, 7):
        for li1 in np.linspace(0.1, 1.9, 7):
            model = TestModel(lr1, li1)
            rho_a = float(spectral_radius_float64(model, method, dec_a, 0)[0])
            rho_b = float(spectral_radius_float64(model, method, dec_b, 0)[0])
            if rho_a > 1.02 and rho_b < 0.98:
                found.append((lr1, li1, rho_a))
    assert len(found) >= 3
    # time stepping at every point found, all of them in one batch (each point its own power iteration)
    lr1, li1, rho_a = map(np.array, zip(*found))
    coefficients = TestModel(lr1, li1).coefficients()
    growth_a = growth_rate(LinearCosimulation(coefficients, dec_a, 0), method)
    growth_b = growth_rate(LinearCosimulation(coefficients, dec_b, 0), method)
    assert growth_a.shape == growth_b.shape == (len(found),)
    for point, grows_a, grows_b in zip(found, growth_a, growth_b):
        assert grows_a == pytest.approx(point[2], rel=2e-2), point
        assert grows_b <= 1.0, point


def test_pendulum_link2_is_the_heavier_at_the_joint_along_link1s_direction_of_motion():
    """gs12_pendulum_stability note: link 1 can move its joint point only along its normal n1, with the
    effective mass J_O1/l1^2 = 1/3 kg; link 2, a free body, resists a force at its end along n1 with
    1/(1/m2 + (r x n1)^2/J2), which at the initial angles (link 2 perpendicular to link 1, so r || n1) is
    m2 = 1 kg.  The linear test model at the pendulum's point with that mass ratio (3) is unstable for
    Baumgarte at k = 1 with link 1 first (the heavier link corrected) and stable with link 2 first, where
    the equal-mass model (am21 = 1) gives 0.999 either way and cannot tell."""
    import math

    import numpy as np

    from icosim.engine.methods import engine_method
    from icosim.problems.linear.spectral import spectral_radius_float64
    from icosim.problems.pendulum.linearised import pendulum_test_model
    from icosim.problems.pendulum.model import PendulumParameters

    p = PendulumParameters()
    n1 = np.array([-math.sin(p.phi1_0), math.cos(p.phi1_0)])
    r = -p.l2 / 2 * np.array([math.cos(p.phi2_0), math.sin(p.phi2_0)])  # link 2's centre of mass -> joint
    m_link1 = p.JO1 / p.l1**2
    r_cross_n1 = r[0] * n1[1] - r[1] * n1[0]
    m_link2 = 1 / (1 / p.m2 + r_cross_n1**2 / p.J2)
    assert m_link1 == pytest.approx(1 / 3) and m_link2 == pytest.approx(1.0)
    H = 1e-3
    point = pendulum_test_model(p, H)
    method = engine_method(make_method("baumgarte", index=1, mu=H), H)

    def rho(am21, scheme):
        model = TestModel(point.lr1, point.li1, am21, point.alr21, point.ali21)
        return float(np.max(spectral_radius_float64(model, method, "ff", 1, scheme=scheme)[0]))

    assert rho(1.0, "gauss-seidel-12") == pytest.approx(0.999, abs=1e-3)
    assert rho(m_link2 / m_link1, "gauss-seidel-12") > 1.5
    assert rho(m_link2 / m_link1, "gauss-seidel-21") < 1


@pytest.mark.parametrize("k", [0, 1, 2])
def test_gauss_seidel_coupling_systems_are_regular_over_the_plane(k):
    """docs/gauss_seidel.md, Sect. 2: the fd Baumgarte system (mu_bar = 1) has a positive determinant and
    the dd condition a derivative of one sign in both orders (positive as the engine forms the condition,
    first subsystem minus second: negative in the paper's second minus first), at every point of the plotted plane in every row
    of Figs. 9-15 and with a ten times lighter subsystem 2: no solve of the Gauss-Seidel schemes is singular."""
    import numpy as np
    from helpers import pair_jacobians

    from icosim.problems.linear.problem import LinearCosimulation

    lr1, li1 = np.meshgrid(np.linspace(-2, 0, 41), np.linspace(0, 2, 41), indexing="ij")
    beta, gamma = 2.0, 1.0  # Baumgarte index 1, mu_bar = 1
    for ratios in ((1, 1, 1), (10, 1, 1), (1, 10, 1), (1, 1, 10), (0.1, 1, 1)):
        c = TestModel(lr1, li1, *ratios).coefficients()
        fd, dd = LinearCosimulation(c, "fd", k), LinearCosimulation(c, "dd", k)
        for fixed in ((True, None), (None, True)):  # the first subsystem leads, or the second
            J = pair_jacobians(fd, None, None, None, None, fixed)
            A = np.concatenate([J["pos"] + beta * J["vel"] + gamma * J["acc"], J["force"]], axis=-2)
            assert np.linalg.det(A).min() > 0.5
            assert pair_jacobians(dd, None, None, None, None, fixed)["force"].min() > 1
