"""The unit fmus/msd_mm (fmus/msd exchanging mm, kN, N/mm, N.s/mm) through fmpy's low-level API: given the same
physical parameters, force and projections (converted with the factors its model description declares), its
outputs converted back to SI are msd's to a few units of rounding."""

import numpy as np
import pytest
from helpers import fmu_instance

pytestmark = pytest.mark.fmu

NAMES = ["m", "c", "d", "x0", "v0", "lambda", "x", "v", "a", "x_set", "v_set", "fail_time"]  # by value reference
SI = {"m": 2.0, "c": 1500.0, "d": 3.0, "x0": 0.012, "v0": -0.3}
H = 1e-3


def si_factors(fmu):
    """Variable name -> the factor of its unit's BaseUnit (SI value = factor * value; 1 where the unit has no
    BaseUnit: msd's are SI) and the unit's name."""
    from fmpy import read_model_description

    md = read_model_description(fmu.unzipDirectory)
    base = {u.name: u.baseUnit.factor if u.baseUnit else 1.0 for u in md.unitDefinitions}
    return {v.name: (base[v.unit], v.unit) for v in md.modelVariables}


def run(tmp_path, unit):
    """Outputs x, v, a in SI after each step: a cubic force (its value and derivatives set), the mass moved by
    x_set and v_set halfway."""
    fmu = fmu_instance(unit, tmp_path / unit)
    factor = {name: f for name, (f, _) in si_factors(fmu).items()}
    ref = {name: NAMES.index(name) for name in NAMES}

    def put(name, value):
        fmu.setReal([ref[name]], [value / factor[name]])

    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    for name, value in SI.items():
        put(name, value)
    fmu.exitInitializationMode()
    out = [[fmu.getReal([ref[n]])[0] * factor[n] for n in ("x", "v", "a")]]
    for j in range(20):
        if j == 10:
            put("x_set", -0.004)
            put("v_set", 0.25)
        put("lambda", 3.0 - 20.0 * (j * H) ** 2)
        derivatives = [-40.0 * j * H, -40.0, 0.0]  # of the force (N/s^k): in the units of lambda's unit per s^k
        fmu.setRealInputDerivatives([ref["lambda"]] * 3, [1, 2, 3], [v / factor["lambda"] for v in derivatives])
        fmu.doStep(j * H, H)
        out.append([fmu.getReal([ref[n]])[0] * factor[n] for n in ("x", "v", "a")])
    fmu.terminate()
    fmu.freeInstance()
    return np.array(out)


def test_the_units_are_engineering_units(tmp_path):
    from fmpy import read_model_description

    fmu = fmu_instance("msd_mm", tmp_path / "unit")
    md = read_model_description(fmu.unzipDirectory)
    fmu.freeInstance()
    want = ["kg", "N/mm", "N.s/mm", "mm", "mm/s", "kN", "mm", "mm/s", "mm/s2", "mm", "mm/s", "s"]
    assert [(v.valueReference, v.name, v.unit) for v in md.modelVariables] == list(zip(range(12), NAMES, want))
    for unit in md.unitDefinitions:  # a display unit in SI: its factor is the BaseUnit's (value_display = f value)
        for display in unit.displayUnits:
            assert display.factor == unit.baseUnit.factor and display.offset == 0.0, unit.name


def test_same_motion_as_msd(tmp_path):
    """Each output to 2e-15 of its largest value (the conversions round; the integration is msd's)."""
    mm, si = run(tmp_path, "msd_mm"), run(tmp_path, "msd")
    scale = np.max(np.abs(si), axis=0)
    assert np.all(np.abs(mm - si) <= 2e-15 * scale), np.max(np.abs(mm - si) / scale, axis=0)
