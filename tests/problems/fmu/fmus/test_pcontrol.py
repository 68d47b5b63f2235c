"""The unit fmus/pcontrol (a proportional controller, u = kp (r - y)) through fmpy's low-level API: its output
follows its inputs at once, and after a step its inputs hold their polynomials' values at the step end (the
Taylor polynomial of the derivatives set), so the output there is kp (r(H) - y(H)) computed by hand."""

import numpy as np
import pytest
from helpers import fmu_instance

pytestmark = pytest.mark.fmu

KP, R, Y, U, FAIL = range(5)  # value references


def test_the_output_follows_the_inputs_and_a_step_moves_them_along_their_polynomials(tmp_path):
    fmu = fmu_instance("pcontrol", tmp_path / "pcontrol")
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([KP], [2.5])
        fmu.exitInitializationMode()
        fmu.setReal([R, Y], [1.0, 0.25])
        assert fmu.getReal([U]) == [2.5 * (1.0 - 0.25)]  # no step needed: direct feedthrough
        H = 0.5
        fmu.setRealInputDerivatives([R, R, Y], [1, 2, 1], [2.0, -4.0, 0.5])
        fmu.doStep(0.0, H)
        r, y = 1.0 + 2.0 * H - 4.0 * H**2 / 2, 0.25 + 0.5 * H
        np.testing.assert_allclose(fmu.getReal([R, Y, U]), [r, y, 2.5 * (r - y)], rtol=1e-15)
        fmu.setReal([FAIL], [0.5])
        with pytest.raises(Exception, match="fmi2DoStep"):  # the shared interface's test hook
            fmu.doStep(0.5, H)
    finally:
        fmu.freeInstance()
